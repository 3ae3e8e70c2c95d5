"""A region's job whose script stops answering must not hold the floor's other regions up to its wall-time limit (in
fast mode the floor's ticks are lockstep: every region waits for every other's commands). After the floor's bounded
wait (``RegionRunner(stall_s=)``) the stalled region is stopped — its robots zero and fixed, then returned — its job
fails with a clear reason (counted in the floor's ``stalled``), and the other region's job runs on to its end.

Deterministic: the stalling script answers three ticks, then sleeps for an hour (without CPU, so its own per-tick
CPU budget never ends it first); the other job starts only after it (so it waits for the stalled region) and is
judged by its outcome only; every wait is bounded and fails naming what it waited for.
"""
import json

import pytest
from mqtt_broker import wait_until
from portal_fixtures import make_portal, skip_verification, wait_for_state

from swarmdeck.console.portal.arenas import ArenaSpec
from swarmdeck.console.portal.exports import JobExports
from swarmdeck.console.portal.region_runner import RegionRunner, region_arena
from swarmdeck.console.portal.runner import ArenaSettings
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.devices.fleet.regions import RegionLayout

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

STALLS = ("import time\n"
          "import numpy as np\n"
          "from swarmdeck.devices import Arena\n"
          "arena = Arena()\n"
          "for _ in range(3):\n"
          "    arena.step_unicycle(np.full(arena.n, 0.05), np.zeros(arena.n))\n"
          "time.sleep(3600)\n")
FAST = ("import numpy as np\n"
        "from swarmdeck.devices import Arena\n"
        "arena = Arena()\n"
        "while True:\n"
        "    arena.step_unicycle(np.full(arena.n, 0.1), np.zeros(arena.n))\n")
START = [[0.2, 0.26, 0.0], [0.2, -0.26, 0.0]]  # region frame
ENDED = ("done", "failed", "cancelled")
WAIT_S = 120


@pytest.fixture
def lab(tmp_path):
    layout = RegionLayout.grid(columns=2)
    spec = region_arena(ArenaSpec("arena", robots=6, fast=True), layout, 3)
    portal = make_portal(tmp_path, arenas=(spec,), fleet=2, max_duration=60.0, max_upload_bytes=64 << 10)
    runner = RegionRunner(portal.service, ArenaSettings(fast=True, seed=5), layout, 3, poll_s=0.2,
                          exports=JobExports(portal.service, video=False), stall_s=3.0)
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


def test_a_stalled_region_is_stopped_its_job_failed_and_the_other_region_goes_on(lab):
    portal, regions = lab
    stalled = queued(portal, "alice", STALLS, robots=2, duration=40.0)
    wait_until(lambda: portal.service.job_state(stalled) == "running", timeout=WAIT_S, what="the stalling job running")
    other = queued(portal, "bob", FAST, robots=2, duration=2.0)
    with portal.client("bob") as c:
        assert wait_for_state(c, other, ENDED, timeout=WAIT_S)["state"] == "done"
    with portal.client("alice") as c:
        job = wait_for_state(c, stalled, ENDED, timeout=WAIT_S)
    region = portal.service.store.get(stalled).placed.split("/")[1]
    assert job["state"] == "failed", job
    assert f"region {region} stalled" in job["reason"] and "no commands for 3 s" in job["reason"], job["reason"]
    run = json.loads((portal.service.job_dir(stalled) / "run.json").read_text())
    assert run["ended_by"] == "stalled" and "stalled" in run["error"], run
    floor = regions.floor
    assert floor.stats.stalled == [region]
    assert regions.fleet_status()["floor"]["stalled"] == [region]
    wait_until(lambda: not floor.busy(), timeout=WAIT_S, what="both regions' robots returned")
    assert floor.stats.outside == 0 and floor.ports.report.collision_pairs == 0
