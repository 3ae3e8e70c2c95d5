"""The portal's arena divided into regions: two researchers' jobs run at once, one per region of one floor, each
with its own recording, result and live view (its region's robots only), its script seeing its region as its arena;
the floor's one barrier keeps every robot in its region. An operator's emergency stop of one region stops its robots
and ends its job while the other region runs on, and latches the region (no job starts there) until released; a
researcher stops their own job by cancelling it.

Deterministic and fast: fixed start poses (the manifest's), the simulated floor in fast mode, and a "slow" script
(it sleeps 10 ms a tick, so it lives at least its duration × 0.3 s of wall time whatever the load) wherever another
job must run while it runs; every wait is bounded and fails naming what it waited for.
"""
import json

import numpy as np
import pytest
from mqtt_broker import wait_until
from portal_fixtures import make_portal, skip_verification, wait_for_state

from swarmdeck.console.portal.arenas import ArenaSpec
from swarmdeck.console.portal.exports import JobExports
from swarmdeck.console.portal.region_runner import RegionRunner, region_arena
from swarmdeck.console.portal.runner import ArenaSettings
from swarmdeck.console.portal.states import ACTIVE
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.core.ports import rows_of
from swarmdeck.devices.fleet.regions import RegionLayout

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

FAST = ("import numpy as np\n"
        "from swarmdeck.devices import Arena\n"
        "arena = Arena()\n"
        "print('BOUNDS', [round(v, 3) for v in arena.config.bounds])\n"
        "while True:\n"
        "    arena.step_unicycle(np.full(arena.n, 0.2), np.zeros(arena.n))\n")
SLOW = ("import time\n"
        "import numpy as np\n"
        "from swarmdeck.devices import Arena\n"
        "arena = Arena()\n"
        "while True:\n"
        "    time.sleep(0.01)\n"
        "    arena.step_unicycle(np.full(arena.n, 0.05), np.zeros(arena.n))\n")
START = [[0.2, 0.26, 0.0], [0.2, -0.26, 0.0]]  # region frame: a short way from where either region parks
ENDED = ("done", "failed", "cancelled")
WAIT_S = 120


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """One portal whose arena is the floor divided 2x1, 3 robots parked per region; shared by the tests."""
    layout = RegionLayout.grid(columns=2)
    spec = region_arena(ArenaSpec("arena", robots=6, fast=True), layout, 3)
    portal = make_portal(tmp_path_factory.mktemp("regions"), arenas=(spec,), fleet=2, max_duration=60.0,
                         max_upload_bytes=64 << 10)
    runner = RegionRunner(portal.service, ArenaSettings(fast=True, seed=5), layout, 3, poll_s=0.2,
                          exports=JobExports(portal.service, video=False))
    portal.service.arena = runner
    runner.start()
    try:
        yield portal, runner
    finally:
        runner.stop()
        portal.server.stop()
        portal.service.close()


def queued(portal, who, source, **kwargs):
    r = portal.submit(who, source=source, filename="job.py", initial_poses=START, **kwargs)
    assert r.status_code == 201, r.text
    jid = r.json()["id"]
    skip_verification(portal, jid)
    return jid


def ended(portal, who, jid):
    with portal.client(who) as c:
        return wait_for_state(c, jid, ENDED, timeout=WAIT_S)


def running(portal, *jids):
    wait_until(lambda: all(portal.service.job_state(j) == "running" for j in jids), timeout=WAIT_S,
               what=f"jobs {list(jids)} running")


def placed(portal, jid):
    return portal.service.store.get(jid).placed


def test_two_jobs_run_at_once_each_in_its_region_and_a_researcher_stops_theirs(lab):
    portal, regions = lab
    a = queued(portal, "alice", FAST, robots=2, duration=2.0)
    b = queued(portal, "bob", SLOW, robots=2, duration=60.0)
    wait_until(lambda: portal.service.job_state(b) in ACTIVE, timeout=WAIT_S, what="bob's job on the floor")
    assert ended(portal, "alice", a)["state"] == "done"
    assert portal.service.job_state(b) in ACTIVE  # both on the floor at once (b's script lives ≥ 18 s of wall time)
    assert {placed(portal, a), placed(portal, b)} == {"arena/r0c0", "arena/r0c1"}
    with portal.client("bob") as c:  # a researcher stops their own job: its region's robots stop at once
        assert c.post(f"/api/jobs/{b}/cancel").status_code == 200
    assert ended(portal, "bob", b)["state"] == "cancelled"
    stats = regions.floor.stats
    assert stats.outside == 0 and stats.barrier_failures == 0
    assert regions.floor.ports.report.collision_pairs == 0
    folder = portal.service.job_dir(a)
    run = json.loads((folder / "run.json").read_text())
    assert run["ended_by"] == "duration" and run["setup"]["ok"] and run["return"]["ok"], run
    with open_recording(folder / "recording.mcap") as rec:
        frames = [f for _, f in rec.frames()]
    assert frames[-1].poses.shape == (2, 3) and tuple(frames[-1].bounds) == (-0.8, 0.8, -1.0, 1.0)
    with portal.client("alice") as c:
        assert "BOUNDS [-0.8, 0.8, -1.0, 1.0]" in c.get(f"/api/jobs/{a}/files/script.log").text
    wait_until(lambda: not regions.floor.busy(), timeout=WAIT_S, what="both regions' robots returned")


def test_an_operator_stops_one_region_the_other_runs_on_and_it_waits_for_the_release(lab):
    portal, regions = lab
    a = queued(portal, "alice", SLOW, robots=2, duration=60.0)
    b = queued(portal, "bob", SLOW, robots=2, duration=8.0)
    running(portal, a, b)
    for jid in (a, b):  # each job's live view: its region's robots only, in its region's frame
        seen = wait_until(lambda j=jid: regions.live.latest_of(j)[2], timeout=WAIT_S, what=f"a live frame of job {jid}")
        assert seen.poses.shape == (2, 3) and tuple(seen.bounds) == (-0.8, 0.8, -1.0, 1.0)
    region = placed(portal, a).split("/")[1]
    with portal.client("alice") as c:
        assert c.post(f"/api/operator/arenas/arena/regions/{region}/estop").status_code == 403
    with portal.client("op1") as c:
        r = c.post("/api/operator/arenas/arena/regions/nowhere/estop")
        assert r.status_code == 404 and "r0c0, r0c1" in r.text
        state = c.post(f"/api/operator/arenas/arena/regions/{region}/estop").json()
    assert {g["name"]: g["stopped"] for g in state["regions"]}[region] is True
    assert ended(portal, "alice", a)["state"] == "cancelled"
    ids = regions.lanes[region].fleet.status()["job_robots"]
    floor = regions.floor

    def where():
        reading = floor.reading()
        return np.asarray(reading.poses)[rows_of(reading.ids, np.asarray(ids))[0], :2].copy()

    stopped_at = where()
    c_job = queued(portal, "alice", FAST, robots=2, duration=1.0)  # must not start on the stopped region
    assert ended(portal, "bob", b)["state"] == "done"  # the other region ran on to its end
    np.testing.assert_allclose(where(), stopped_at, atol=1e-9)  # the stopped region's robots stayed where they stopped
    assert ended(portal, "alice", c_job)["state"] == "done"
    assert placed(portal, c_job) != f"arena/{region}"
    with portal.client("op1") as c:
        state = c.post(f"/api/operator/arenas/arena/regions/{region}/release").json()
        assert {g["name"]: g["stopped"] for g in state["regions"]}[region] is False
        assert c.post(f"/api/operator/arenas/arena/regions/{region}/release").status_code == 409
        audit = [e["action"] for e in c.get("/api/operator/audit").json()]
    assert f"emergency stop of region arena/{region}" in audit
    assert f"release emergency stop of region arena/{region}" in audit
    wait_until(lambda: not floor.busy(), timeout=WAIT_S, what="the released region's robots returned")
    assert floor.stats.outside == 0 and floor.ports.report.collision_pairs == 0
