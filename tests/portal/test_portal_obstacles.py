"""The portal's arena with line-segment obstacles (`swarmdeck server --obstacles`): a job whose start poses lie
behind a wall is set up round it, runs with the obstacles in its barrier and recording (the live view's Frames
carry them), and its robots dock again, nobody touching the wall; a bad obstacles file is a usage error."""
import json

import pytest
from portal_fixtures import skip_verification, wait_for_state

from swarmdeck.console.cli import main
from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.core.obstacles import Obstacles, point_segment_distance

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

WALL = Obstacles([[[-1.0, -0.35], [1.0, -0.35]]])  # between the bottom chargers and the start poses
DOWN = ("import numpy as np\ndef experiment(arena):\n    while True:\n"
        "        arena.set_unicycle(np.full(arena.n, 0.15), np.zeros(arena.n))\n        arena.step()\n")
POSES = [[-0.3, -0.05, -1.5708], [0.3, -0.05, -1.5708]]


def test_a_job_behind_a_wall_is_set_up_round_it_and_kept_off_it(portal):
    svc = portal.service
    runner = ArenaRunner(svc, ArenaSettings(fast=True, fleet=4, seed=1, obstacles=WALL), poll_s=0.1)
    svc.arena = runner
    runner.start()
    try:
        jid = portal.submit("alice", source=DOWN, robots=2, duration=3.0, initial_poses=POSES).json()["id"]
        skip_verification(portal, jid)
        with portal.client("alice") as c:
            # set-up, 3 s of job and return, simulated as fast as a loaded machine computes them: a generous bound
            job = wait_for_state(c, jid, ("done", "failed"), timeout=900.0)
            assert job["state"] == "done", c.get(f"/api/jobs/{jid}").json()
        run = json.loads((svc.job_dir(jid) / "run.json").read_text())
        assert run["setup"]["ok"] and run["return"]["ok"], json.dumps({k: run[k] for k in ("setup", "return")})
        with open_recording(svc.job_dir(jid) / "recording.mcap") as rec:
            frames = [f for _, f in rec.frames()]
        assert frames and all(f.obstacles == WALL for f in frames)
        d = min(point_segment_distance(f.poses[:, :2], WALL.segments).min() for f in frames)
        assert d > 0.055  # driven at the wall for 3 s, the barrier kept every body off it
    finally:
        runner.stop()


def test_server_refuses_a_bad_obstacles_file(tmp_path, capsys):
    bad = tmp_path / "walls.toml"
    bad.write_text("[arena]\nobstacles = [[[-0.5, -0.97], [0.5, -0.97]]]\n")  # over the bottom charger slots
    assert main(["server", "--data", str(tmp_path / "data"), "--port", "0", "--obstacles", str(bad),
                 "--trusted"]) == 2
    assert "crosses charger slot" in capsys.readouterr().err
