"""Verification runs from the start poses the arena will use (issue 24, item 2): the manifest's, else the script's
own initial conditions (checked like the manifest's), else random ones — one rule shared with the arena runner —
plus a seeded set-up error within the fleet's tolerance (2 cm, 5°); a script asking for another robot count than
declared is refused at once."""
import textwrap

import numpy as np
import pytest
from portal_fixtures import wait_for_state

from swarmdeck.console.portal.workers import VerificationWorkers
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor
from swarmdeck.console.sandbox.start_poses import MIN_SEPARATION, arena_start, check_initial_poses, perturb
from swarmdeck.console.sandbox.verification import ACCEPTED, BYPASS, REJECTED, VerificationConfig, verify
from swarmdeck.core.kinematics import wrap_angle
from swarmdeck.devices.fleet.setup import ACCEPT_HEADING, ACCEPT_POSITION

confined = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

FACING = ((-0.115, 0.0, 0.0), (0.115, 0.0, np.pi))  # 0.23 m apart, facing each other
OPEN_LOOP = """
import numpy as np
def experiment(arena):
    while True:  # open loop: forward at 8 cm/s, whatever the poses (8 cm in the declared second)
        arena.set_unicycle(np.full(arena.n, 0.08), np.zeros(arena.n))
        arena.step()
"""


def random_poses(n):
    return np.array([[0.5 * k, 0.5, 0.0] for k in range(n)])


def test_the_rule_takes_the_manifest_then_the_script_then_random_poses():
    script = np.array([[0.0, -0.5, 0.0], [0.5, -0.5, 0.0]])
    both = arena_start(2, 2, FACING, script, random_poses)
    assert both.source == "manifest" and np.allclose(both.poses, np.array(FACING) * [1, 1, 1])
    own = arena_start(2, 2, None, script, random_poses)
    assert own.source == "script" and np.array_equal(own.poses, script)
    drawn = arena_start(2, None, None, None, random_poses)
    assert drawn.source == "random" and np.array_equal(drawn.poses, random_poses(2))
    with pytest.raises(ValueError, match="the script asks for 500 robots but the manifest declares 1"):
        arena_start(500, 1, None, None, random_poses)
    with pytest.raises(ValueError, match="the script asks for 3 robots but --robots declares 2"):
        arena_start(3, 2, None, None, random_poses, declared_by="--robots")


@pytest.mark.parametrize("poses,words", [
    ([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]], r"poses 0 \(0.000, 0.000\) and 1 \(0.100, 0.000\) are 0.100 m apart"),
    ([[0.0, 0.0, 0.0], [2.0, 0.5, 0.0]], r"pose 1 \(2.000, 0.500, 0.000\) is outside the arena"),
    ([[0.0, 0.0, 0.0]], "1 rows but the arena has 2 robots"),
    ([[0.0, 0.0, np.nan], [1.0, 0.0, 0.0]], "NaN or inf"),
])
def test_bad_initial_poses_are_refused_naming_the_pose(poses, words):
    with pytest.raises(ValueError, match=words):
        check_initial_poses(poses, 2, name="the script's initial conditions")


def test_exactly_the_minimum_separation_is_allowed():
    assert check_initial_poses(FACING, 2).shape == (2, 3) and MIN_SEPARATION == 0.23


def test_the_set_up_error_stays_within_the_fleets_tolerance():
    poses = np.tile(np.array(FACING), (500, 1))
    moved = perturb(poses, np.random.default_rng(7))
    shift = np.hypot(*(moved[:, :2] - poses[:, :2]).T)
    turn = np.abs(wrap_angle(moved[:, 2] - poses[:, 2]))
    assert shift.max() <= ACCEPT_POSITION and turn.max() <= ACCEPT_HEADING
    assert shift.max() > 0.5 * ACCEPT_POSITION and turn.max() > 0.5 * ACCEPT_HEADING  # it does move them
    assert np.array_equal(perturb(poses, np.random.default_rng(7)), moved)  # seeded
    assert np.array_equal(poses, np.tile(np.array(FACING), (500, 1)))  # the argument is untouched


def near(run_poses, poses):
    p, q = np.asarray(run_poses), np.asarray(poses)
    return (np.hypot(*(p[:, :2] - q[:, :2]).T).max() <= ACCEPT_POSITION + 1e-6
            and np.abs(wrap_angle(p[:, 2] - q[:, 2])).max() <= ACCEPT_HEADING + 1e-6)


@confined
def test_an_honest_open_loop_script_is_verified_from_the_manifest_poses(tmp_path):
    script = tmp_path / "forward.py"
    script.write_text(textwrap.dedent(OPEN_LOOP))
    config = VerificationConfig(n_robots=2, duration=1.0, runs=2, seed=5, initial_poses=FACING)
    report = verify([script], config, SerialExecutor())
    runs = report.scripts[0]["runs"]
    assert all(r["start_poses_from"] == "manifest" and near(r["start_poses"], FACING) for r in runs)
    assert report.verdict == ACCEPTED  # not "may bypass": head-on, the robots touch without the barrier
    raw = [r for r in runs if r["mode"] == "raw"]
    assert all(r["contacts"]["count"] > 0 and r["safety_score"] < 0.99 for r in raw)
    assert report.to_dict()["config"]["initial_poses"] == [list(p) for p in FACING]


@confined
def test_the_script_initial_conditions_are_used_when_the_manifest_has_none(tmp_path):
    script = tmp_path / "own.py"
    script.write_text("import numpy as np\nimport rps.robotarium as robotarium\n"
                      "r = robotarium.Robotarium(number_of_robots=2, initial_conditions=np.array("
                      "[[-0.5, 0.5], [0.3, 0.3], [0.0, 1.0]]))\nr.get_poses()\nr.step()\n")
    report = verify([script], VerificationConfig(n_robots=2, duration=0.3, runs=1), SerialExecutor())
    assert report.verdict == BYPASS
    own = [[-0.5, 0.3, 0.0], [0.5, 0.3, 1.0]]
    assert all(r["start_poses_from"] == "script" and near(r["start_poses"], own) for r in report.scripts[0]["runs"])


@confined
@pytest.mark.parametrize("columns,words", [
    ("[[0.0, 0.1], [0.0, 0.0], [0.0, 0.0]]", "poses 0 (0.000, 0.000) and 1 (0.100, 0.000) are 0.100 m apart"),
    ("[[0.0, 2.5], [0.0, 0.0], [0.0, 0.0]]", "pose 1 (2.500, 0.000, 0.000) is outside the arena"),
])
def test_script_initial_conditions_that_overlap_or_lie_outside_are_refused_by_name(tmp_path, columns, words):
    script = tmp_path / "bad.py"
    script.write_text("import numpy as np\nimport rps.robotarium as robotarium\n"
                      f"r = robotarium.Robotarium(number_of_robots=2, initial_conditions=np.array({columns}))\n"
                      "r.get_poses()\nr.step()\n")  # (rps's order: get_poses() before step())
    report = verify([script], VerificationConfig(n_robots=2, duration=0.3, runs=1), SerialExecutor())
    assert report.verdict == REJECTED
    reason = report.to_dict()["reasons"][0]
    assert "the script's initial conditions" in reason and words in reason, reason
    assert all(r["ended_by"] == "arena" and r["ticks"] == 0 for r in report.scripts[0]["runs"])


@confined
def test_the_portal_verifies_a_job_from_its_manifest_poses(portal):  # noqa: F811
    workers = VerificationWorkers(portal.service, SerialExecutor(), poll_s=0.2).start()
    try:
        r = portal.submit("alice", source=textwrap.dedent(OPEN_LOOP), filename="forward.py", robots=2, duration=1.0,
                          initial_poses=[list(p) for p in FACING], no_barrier=True)
        assert r.status_code == 201, r.text
        with portal.client("alice") as c:
            job = wait_for_state(c, r.json()["id"], ("in arena queue", "rejected"), timeout=120)
            report = c.get(f"/api/jobs/{job['id']}/report").json()
    finally:
        workers.stop()
    assert job["verdict"] == ACCEPTED and job["safety_score"] < 0.99, job  # no bypass for a head-on drive
    runs = report["scripts"][0]["runs"]
    assert all(r["start_poses_from"] == "manifest" and near(r["start_poses"], FACING) for r in runs)
    assert any(r["contacts"]["count"] for r in runs if r["mode"] == "raw")
