"""Verification with the arena's line-segment obstacles: robots touching a segment count as contacts (a raw run
that drives into a wall refuses the bypass, the wrapped run keeps off it and is accepted), random start poses keep
clear of the segments, and start poses on a segment are refused naming it."""
import textwrap

import numpy as np
import pytest

from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor
from swarmdeck.console.sandbox.verification import ACCEPTED, VerificationConfig, verify
from swarmdeck.core.obstacles import ObstacleError, Obstacles

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

WALL = Obstacles([[[-1.5, -0.3], [1.5, -0.3]]])
START = ((-0.6, 0.4, -np.pi / 2), (0.0, 0.4, -np.pi / 2), (0.6, 0.4, -np.pi / 2))
DOWN = """
import numpy as np
def experiment(arena):
    while True:  # straight down, through the wall if nothing stops them
        arena.set_unicycle(np.full(arena.n, 0.15), np.zeros(arena.n))
        arena.step()
"""


def test_driving_into_a_wall_is_a_contact_without_the_barrier_and_none_with_it(tmp_path):
    path = tmp_path / "down.py"
    path.write_text(textwrap.dedent(DOWN))
    cfg = VerificationConfig(n_robots=3, duration=8.0, runs=1, seed=2, initial_poses=START, obstacles=WALL,
                             paced_runs=0)
    report = verify([path], cfg, SerialExecutor())
    script = report.scripts[0]
    assert report.verdict == ACCEPTED, script["reasons"]
    raw = [r for r in script["runs"] if r["mode"] == "raw"]
    wrapped = [r for r in script["runs"] if r["mode"] == "wrapped"]
    assert all(r["obstacle_contact_steps"] > 0 for r in raw)
    assert all(r["obstacle_contact_steps"] == 0 for r in wrapped)
    assert any("touched obstacles" in why for why in script["bypass_refused_because"])
    assert report.to_dict()["config"]["obstacles"] == WALL.to_list()


def test_start_poses_on_a_segment_are_refused_naming_it():
    with pytest.raises(ObstacleError, match=r"segment 0 .*crosses start pose 1"):
        VerificationConfig(n_robots=3, initial_poses=((-0.6, 0.4, 0.0), (0.0, -0.28, 0.0), (0.6, 0.4, 0.0)),
                           obstacles=WALL)


def test_random_start_poses_keep_clear_and_the_script_runs_accepted(tmp_path):
    path = tmp_path / "still.py"
    path.write_text("def experiment(arena):\n    while True:\n        arena.step()\n")
    cfg = VerificationConfig(n_robots=8, duration=1.0, runs=1, seed=5, obstacles=WALL, paced_runs=0)
    report = verify([path], cfg, SerialExecutor())
    assert report.verdict != "rejected", report.scripts[0]["reasons"]
    for run in report.scripts[0]["runs"]:
        poses = np.array(run["start_poses"])
        assert np.all(np.abs(poses[:, 1] + 0.3) > 0.1)
