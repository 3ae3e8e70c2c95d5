"""The portal's arena records the robots' sensors (`swarmdeck server --sensors`, ``ArenaSettings.sensors``): a
job's Frames carry the seven ToF distances per robot, hitting the floor's obstacle straight ahead; without the
option they carry none."""
import json

import numpy as np
import pytest
from portal_fixtures import skip_verification, wait_for_state

from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.core.obstacles import Obstacles

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

WALL = Obstacles([[[-0.6, 0.35], [0.6, 0.35]]])  # 0.4 m ahead of the robots, facing it
STILL = ("import numpy as np\ndef experiment(arena):\n    while True:\n"
         "        arena.set_unicycle(np.zeros(arena.n), np.zeros(arena.n))\n        arena.step()\n")
POSES = [[-0.3, -0.05, 1.5708], [0.3, -0.05, 1.5708]]


def run_job(portal, settings):
    svc = portal.service
    runner = ArenaRunner(svc, settings, poll_s=0.1)
    svc.arena = runner
    runner.start()
    try:
        jid = portal.submit("alice", source=STILL, robots=2, duration=1.0, initial_poses=POSES).json()["id"]
        skip_verification(portal, jid)
        with portal.client("alice") as c:
            assert wait_for_state(c, jid, ("done", "failed"))["state"] == "done", c.get(f"/api/jobs/{jid}").json()
        assert json.loads((svc.job_dir(jid) / "run.json").read_text())["setup"]["ok"]
        with open_recording(svc.job_dir(jid) / "recording.mcap") as rec:
            return [f for _, f in rec.frames()]
    finally:
        runner.stop()


def test_a_job_on_an_arena_with_sensors_records_them(portal):
    frames = run_job(portal, ArenaSettings(fast=True, fleet=4, seed=1, obstacles=WALL, sensors=True))
    assert frames and all(f.sensors is not None for f in frames)
    last = frames[-1]
    assert last.sensors.distances.shape == (2, 7)
    forward = int(np.argmin(np.abs(last.sensors.sensor_poses[:, 2])))  # the sensor looking straight ahead
    ahead = last.sensors.distances[:, forward]
    seen = ahead[ahead >= 0]  # -1: a dropout
    # the wall is 0.4 m ahead of each robot's axle; the sensor sits on the body, a few cm forward (3 % error)
    assert seen.size and np.all((seen > 0.25) & (seen < 0.45)), ahead


def test_a_job_on_an_arena_without_sensors_records_none(portal):
    frames = run_job(portal, ArenaSettings(fast=True, fleet=4, seed=1))
    assert frames and all(f.sensors is None for f in frames)
