"""The rps facade: an unchanged rps script runs on swarmdeck, without rps's defects."""
import sys
from pathlib import Path

import numpy as np
import pytest

from swarmdeck.console.cli import main as cli_main
from swarmdeck.devices.rps import rps_aliases
from swarmdeck.devices.runner import run_experiment

SCRIPT = Path(__file__).resolve().parents[1] / "data" / "rps" / "si_barriers_with_boundary.py"


def test_rps_script_runs_unchanged_and_reaches_its_goals(capsys):
    result = run_experiment(SCRIPT, duration=120.0, seed=3)
    assert result.ok, result.error
    (report,) = result.reports
    assert report.validation.steps_with_collision == 0
    assert report.validation.steps < 120 / 0.033  # the while-loop ended: every robot at its goal
    assert "rps" not in sys.modules  # the aliases are gone after the run


def test_cli_runs_rps_script(capsys):
    assert cli_main(["run", str(SCRIPT), "--duration", "120", "--seed", "3"]) == 0
    assert "collisions: 0 pair-steps" in capsys.readouterr().out


def test_robotarium_object_has_no_rps_defects():
    with rps_aliases():
        import rps.robotarium as robotarium
        from rps.utilities.barrier_certificates import create_single_integrator_barrier_certificate

        with pytest.raises(ValueError, match="float"):
            robotarium.Robotarium(2, initial_conditions=np.array([[0, 1], [0, 0], [0, 0]]), sim_in_real_time=False)
        r = robotarium.Robotarium(2, initial_conditions=np.array([[0.0, 0.5], [0.0, 0.0], [0.0, 0.0]]), sim_in_real_time=False,
                                    enforce_call_order=False)  # reads the poses twice to show they are copies
        x = r.get_poses()
        x[0, 0] = 99.0
        assert r.get_poses()[0, 0] == 0.0  # a copy, not the internal array
        vel = np.array([[0.1, 0.1], [0.0, 0.0]])
        keep = vel.copy()
        r.set_velocities(np.arange(2), vel)
        r.step()
        np.testing.assert_array_equal(vel, keep)
        cert = create_single_integrator_barrier_certificate()
        dxi = np.array([[0.2, -0.2], [0.0, 0.0]])
        pts = np.array([[0.0, 0.2], [0.0, 0.0]])
        keep_dxi, keep_pts = dxi.copy(), pts.copy()
        safe = cert(dxi, pts)
        np.testing.assert_array_equal(dxi, keep_dxi)
        np.testing.assert_array_equal(pts, keep_pts)
        assert safe[0, 0] < 0.2  # approaching pair slowed
    assert "rps" not in sys.modules


@pytest.mark.parametrize("ids", [[0.5, 1.0], ["a", "b"], [True, False]])
def test_set_velocities_rejects_ids_that_are_not_indices(ids):
    from swarmdeck.devices.rps.robotarium import Robotarium

    r = Robotarium(number_of_robots=3, sim_in_real_time=False)
    with pytest.raises(ValueError, match="ids"):
        r.set_velocities(np.array(ids), np.zeros((2, 2)))
    r.set_velocities(np.array([0.0, 2.0]), np.zeros((2, 2)))  # whole numbers as floats are fine
    r.set_velocities(np.array([True, False, True]), np.zeros((2, 2)))
