"""The portal's arena divided into regions: two researchers' jobs run at once, one per region of one floor, each
with its own recording and result, its script seeing its region as its arena; the floor's one barrier keeps every
robot in its region (no contact); an e-stop of one region ends only that job."""
import json

import pytest
from mqtt_broker import wait_until
from portal_fixtures import wait_for_state

from swarmdeck.console.portal.region_runner import RegionRunner
from swarmdeck.console.portal.runner import ArenaSettings
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.devices.fleet.regions import RegionLayout

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

RAM = ("import numpy as np\n"
       "from swarmdeck.devices import Arena\n"
       "arena = Arena()\n"
       "print('BOUNDS', [round(v, 3) for v in arena.config.bounds])\n"
       "while True:\n"
       "    arena.step_unicycle(np.full(arena.n, 0.2), np.zeros(arena.n))\n")


@pytest.fixture
def regions(portal):
    runner = RegionRunner(portal.service, ArenaSettings(fast=True, seed=5), RegionLayout.grid(columns=2), 3,
                          poll_s=0.2)
    portal.service.arena = runner
    runner.start()
    yield runner
    runner.stop()


def queued(portal, who, **kwargs):
    svc = portal.service
    jid = portal.submit(who, source=RAM, filename="ram.py", **kwargs).json()["id"]
    with svc.db.transaction() as tx:
        svc.db.transition(tx, jid, "verifying")
        svc.db.transition(tx, jid, "awaiting approval", verdict="accepted")
        svc.db.transition(tx, jid, "in arena queue")
    svc.notify()
    return jid


def test_two_jobs_run_at_once_each_in_its_region(portal, regions):
    a = queued(portal, "alice", robots=2, duration=20.0)
    b = queued(portal, "bob", robots=2, duration=20.0)
    both = wait_until(lambda: sorted(j for j in regions.current_jobs.values() if j is not None) == sorted([a, b])
                      and all(portal.service.job_state(j) == "running" for j in (a, b)), timeout=300,
                      what="both jobs running at once")
    assert both
    for who, jid in (("alice", a), ("bob", b)):
        with portal.client(who) as c:
            job = wait_for_state(c, jid, ("done", "failed", "cancelled"), timeout=300)
            assert job["state"] == "done", job
            log = c.get(f"/api/jobs/{jid}/files/script.log").text
    stats = regions.floor.stats
    assert stats.outside == 0 and stats.barrier_failures == 0
    assert regions.floor.ports.report.collision_pairs == 0
    for jid in (a, b):
        folder = portal.service.job_dir(jid)
        run = json.loads((folder / "run.json").read_text())
        assert run["ended_by"] == "duration" and run["setup"]["ok"] and run["return"]["ok"], run
        with open_recording(folder / "recording.mcap") as rec:
            frames = [f for _, f in rec.frames()]
        assert frames[-1].poses.shape == (2, 3) and tuple(frames[-1].bounds) == (-0.8, 0.8, -1.0, 1.0)
    assert "BOUNDS [-0.8, 0.8, -1.0, 1.0]" in log


def test_an_emergency_stop_of_one_region_ends_only_its_job(portal, regions):
    a = queued(portal, "alice", robots=2, duration=30.0)
    b = queued(portal, "bob", robots=2, duration=4.0)
    wait_until(lambda: all(portal.service.job_state(j) == "running" for j in (a, b)), timeout=300,
               what="both jobs running at once")
    region = next(name for name, j in regions.current_jobs.items() if j == a)
    assert regions.estop_region(region) == a
    with portal.client("alice") as c:
        assert wait_for_state(c, a, ("done", "failed", "cancelled"), timeout=300)["state"] in ("cancelled", "failed")
    with portal.client("bob") as c:
        assert wait_for_state(c, b, ("done", "failed", "cancelled"), timeout=300)["state"] == "done"
    assert regions.floor.stats.stopped == [region]
