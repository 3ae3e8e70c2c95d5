"""Every example of the Robotarium Python simulator — rps 2.0 (``master``) and the earlier ``dev`` branch — runs
unchanged under ``swarmdeck run`` with the outcome it has under its own rps (issue 28 item 4).

The scripts are the repository's own files (tests/data/rps2_examples, README there: repository, commits, paths).
Examples that run a fixed number of iterations are shortened with the run's duration (``swarmdeck run
--duration``; the script is not edited), the others run until their own loop ends. Outcomes:

* ``goals`` — the script's own loop ended (every robot at its goal, by the script's own ``at_pose``/``at_position``),
  no collision, no robot outside the arena; a 2.x script's ``debug()`` says it will run on the Robotarium;
* ``runs`` — the script ran to the declared duration without an error, no collision, no robot outside, robots moved;
* ``consensus`` — as ``runs``, and the robots drew together (the spread of their positions shrank);
* ``fails`` — the example fails under its own rps too (dev's consensus_fewer_errors.py uses ``dxi`` before it is
  defined): swarmdeck reports the same error on the script's line.

Examples that need rps 2.x's sensors or obstacles are in test_devices_rps2_examples_sensors.py. Marks name what else
an example exercises (``rps2_plotting``: it draws on the figure, headless here).
"""
from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest
from marbler_fixtures import swarmdeck_cli
from rps2_examples import DEBUG_ACCEPTED, DEBUG_HEAD, EXAMPLES, run_example

from swarmdeck.core.constants import AXLE_LENGTH, GTERNAL_BASE_LENGTH

SHORT = 6.0  # s simulated: enough for every fixed-length example to show its behaviour
GOALS = 90.0  # s: a cap the goal-seeking examples never reach (they take 12–30 s)
PLOT = pytest.mark.rps2_plotting

CASES = [
    # rps 2.0 (master)
    ("master/barrier_certificates/si_barriers.py", "runs", ()),
    ("master/barrier_certificates/uni_barriers.py", "runs", ()),
    ("master/consensus/consensus.py", "consensus", ()),
    ("master/consensus/consensus_fewer_errors.py", "consensus", ()),
    ("master/data_saving/leader_follower_save_data.py", "runs", ()),
    ("master/formation_control/formation_control.py", "runs", ()),
    ("master/go_to_goal/go_to_point_si.py", "goals", ()),
    ("master/go_to_goal/go_to_point_uni.py", "goals", ()),
    ("master/go_to_goal/go_to_pose_clf.py", "goals", ()),
    ("master/go_to_goal/go_to_pose_hybrid.py", "goals", ()),
    ("master/leader_follower/leader_follower.py", "runs", ()),
    ("master/plotting/barriers_with_plotting.py", "runs", (PLOT,)),
    ("master/plotting/go_to_pose_with_plotting.py", "runs", (PLOT,)),
    ("master/plotting/leader_follower_with_plotting.py", "runs", (PLOT,)),
    # rps 1.x (dev)
    ("dev/barrier_certificates/barrier_certificates.py", "runs", ()),
    ("dev/barrier_certificates/si_barriers_with_boundary.py", "runs", ()),
    ("dev/barrier_certificates/uni_barriers_with_boundary.py", "runs", ()),
    ("dev/barrier_certificates/uni_dd_barriers_with_boundary.py", "runs", ()),
    ("dev/consensus/consensus.py", "consensus", ()),
    ("dev/consensus/consensus_fewer_errors.py", "fails", ()),
    ("dev/data_saving/leader_follower_save_data.py", "runs", ()),
    ("dev/formation_control/formation_control.py", "runs", ()),
    ("dev/go_to_point/si_go_to_point.py", "goals", ()),
    ("dev/go_to_point/uni_go_to_point.py", "goals", ()),
    ("dev/go_to_pose/uni_go_to_pose_clf.py", "goals", ()),
    ("dev/go_to_pose/uni_go_to_pose_hybrid.py", "goals", ()),
    ("dev/leader_follower_static/leader_follower.py", "runs", ()),
    ("dev/plotting/barrier_certificates_with_plotting.py", "runs", (PLOT,)),
    ("dev/plotting/leader_follower_with_plotting.py", "runs", (PLOT,)),
    ("dev/plotting/si_go_to_point_gt.py", "goals", (PLOT,)),
    ("dev/plotting/si_go_to_point_with_plotting.py", "goals", (PLOT,)),
    ("dev/plotting/uni_go_to_pose_hybrid_with_plotting.py", "goals", (PLOT,)),
]


def _spread(poses: np.ndarray) -> float:
    return float(np.linalg.norm(poses[:, :2] - poses[:, :2].mean(axis=0), axis=1).max())


@pytest.mark.parametrize("name, outcome", [pytest.param(n, o, marks=m, id=n) for n, o, m in CASES])
def test_example_runs_unchanged_with_its_outcome(name, outcome, tmp_path):
    run = run_example(name, tmp_path, duration=GOALS if outcome == "goals" else SHORT)
    result = run.result
    if outcome == "fails":
        assert not result.ok
        assert "NameError" in result.error_line and "'dxi'" in result.error_line
        assert result.error_line.startswith("consensus_fewer_errors.py:49")
        return
    assert result.ok, result.error
    report = run.report
    v = report.validation
    assert v.steps_with_collision == 0 and v.steps_with_boundary == 0, str(report)
    # the robot model of the script's generation: the GTernal for 2.x, the GRITSBot for 1.x (REFERENCE.md §1, §15)
    assert run.arenas[0].params.axle_length == (GTERNAL_BASE_LENGTH if name.startswith("master/") else AXLE_LENGTH)
    if outcome == "goals":
        assert report.time < GOALS - 1.0, "the script's own loop ended: every robot reached its goal"
        if name.startswith("master/"):
            assert DEBUG_HEAD in run.output and any(verdict in run.output for verdict in DEBUG_ACCEPTED), run.output
        return
    assert report.time >= SHORT - 0.05, "ran to the declared duration"
    assert np.linalg.norm(run.end[:, :2] - run.start[:, :2], axis=1).max() > 0.05, "the robots moved"
    if outcome == "consensus":
        assert _spread(run.end) < 0.8 * _spread(run.start)


def test_a_2x_example_runs_under_swarmdeck_run_and_in_the_sandbox(tmp_path):
    """The CLI, in process and jailed: the same example ends at its goals, with rps 2.x's debug() verdict."""
    folder = tmp_path / "go_to_goal"
    shutil.copytree(EXAMPLES / "master" / "go_to_goal", folder)
    for extra in ((), ("--sandbox",)):
        done = subprocess.run([*swarmdeck_cli(), "run", str(folder / "go_to_point_si.py"),
                               "--duration", str(GOALS), "--seed", "2", *extra],
                              capture_output=True, text=True, cwd=folder, timeout=600)
        assert done.returncode == 0, done.stderr + done.stdout
        assert DEBUG_HEAD in done.stdout and any(verdict in done.stdout for verdict in DEBUG_ACCEPTED), done.stdout
        assert "collisions: 0 pair-steps" in done.stdout
        time = float(done.stdout.split("simulated time:")[1].split()[0])
        assert time < GOALS - 1.0, done.stdout
