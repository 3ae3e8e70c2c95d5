"""Verification against the exact region a job will get, end to end through the portal: on an arena whose floor is
divided into regions, a job is verified in its region as its script will see it (the region's local bounds: walls,
start poses, ``arena.config.bounds``) — start poses inside the floor but outside the region are refused, a script
that drives out of its region is held at the region's walls in verification as on the floor — and the plan puts a
job only on regions of exactly the bounds it was verified against."""
import pytest
from portal_fixtures import make_portal, wait_for_state

from swarmdeck.console.portal.arenas import ArenaSpec
from swarmdeck.console.portal.region_runner import region_arena
from swarmdeck.console.portal.scheduler import Lane, Pending, plan
from swarmdeck.console.portal.workers import VerificationWorkers
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor
from swarmdeck.core.bounds import Bounds
from swarmdeck.devices.fleet.regions import RegionLayout

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

REGION = (-0.8, 0.8, -1.0, 1.0)  # a 2x1 grid's region as its job sees it
SAYS_BOUNDS = ("import numpy as np\n"
               "from swarmdeck.devices import Arena\n"
               "arena = Arena()\n"
               "print('BOUNDS', [round(v, 3) for v in arena.config.bounds])\n"
               "while True:\n"
               "    arena.step_unicycle(np.full(arena.n, 0.2), np.zeros(arena.n))\n")  # full ahead, at the wall


@pytest.fixture
def portal(tmp_path):
    spec = region_arena(ArenaSpec("arena", robots=6), RegionLayout.grid(columns=2), 3)
    p = make_portal(tmp_path, arenas=(spec,), fleet=6, max_duration=60.0, max_upload_bytes=64 << 10)
    workers = VerificationWorkers(p.service, SerialExecutor(), poll_s=0.2).start()
    try:
        yield p
    finally:
        workers.stop()
        p.server.stop()
        p.service.close()


def test_a_job_is_verified_in_the_region_it_will_get(portal):
    outside = portal.submit("alice", source=SAYS_BOUNDS, filename="job.py", robots=2, duration=1.0,
                            initial_poses=[[1.0, 0.3, 0.0], [1.0, -0.3, 0.0]]).json()["id"]  # on the floor, not in a region
    inside = portal.submit("bob", source=SAYS_BOUNDS, filename="job.py", robots=2, duration=3.0,
                           initial_poses=[[0.5, 0.3, 0.0], [0.5, -0.3, 0.0]]).json()["id"]  # drives into the wall
    with portal.client("alice") as c:
        job = wait_for_state(c, outside, ("rejected", "failed"), timeout=120)
    assert "initial_poses" in job["reason"] and "0.8" in job["reason"], job["reason"]
    with portal.client("bob") as c:
        job = wait_for_state(c, inside, ("in arena queue", "rejected", "failed"), timeout=120)
        assert job["state"] == "in arena queue", job
        report = c.get(f"/api/jobs/{inside}/report").json()
    assert report["config"]["bounds"] == list(REGION), report["config"]
    assert portal.service.job_bounds(portal.service.store.get(inside)) == Bounds(*REGION)


def test_a_job_goes_only_on_a_region_of_the_bounds_it_was_verified_against():
    west, east = Bounds(-0.6, 0.6, -1.0, 1.0), Bounds(-1.0, 1.0, -1.0, 1.0)
    spec = ArenaSpec("big", robots=8, slots=2, slot_names=("west", "east"), slot_robots=(4, 4),
                     slot_bounds=(west, east))
    assert spec.job_bounds(2) == west  # equal capacity: the smaller region
    assert ArenaSpec("plain").job_bounds(2) == Bounds(-1.6, 1.6, -1.0, 1.0)
    lanes = [Lane("big", k, "simulated", 4, [], tuple(spec.slot_shape(k))) for k in range(2)]
    out = plan([Pending(1, 1, 2, 30.0, bounds=tuple(east)), Pending(2, 2, 2, 30.0, bounds=tuple(west)),
                Pending(3, 3, 2, 30.0, bounds=tuple(east))], lanes, [], 1000.0, {})
    assert (out[1].slot, out[2].slot, out[3].slot) == (1, 0, 1)
    assert out[1].start == out[2].start == 1000.0 and out[3].start > 1000.0  # waits for the east region
