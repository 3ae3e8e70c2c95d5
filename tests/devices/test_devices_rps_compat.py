"""rps compatibility: rps scripts that finish under rps finish under `swarmdeck run` (issue 14, items 5–7).

The scripts in tests/data/rps are written in the style of rps's examples (numpy 1's np.mat, the
backwards-motion heading map, the differential-drive barrier, plotting on ``r.axes``)."""
from pathlib import Path

import numpy as np
import pytest

from swarmdeck.devices.rps import NP_MAT_NOTE, rps_aliases
from swarmdeck.devices.runner import run_experiment

DATA = Path(__file__).resolve().parents[1] / "data" / "rps"
CAP = 60.0  # s: far beyond what either script needs


def _finished(result) -> None:
    assert result.ok, result.error
    (report,) = result.reports
    assert report.time < CAP - 1.0, "the script's own loop ended (it did not run into the cap)"
    assert report.validation.steps_with_collision == 0


def test_backwards_motion_go_to_point_finishes_and_np_mat_is_provided_for_the_run_only():
    had_mat = hasattr(np, "mat")
    result = run_experiment(DATA / "go_to_point_backwards.py", duration=CAP, seed=1)
    _finished(result)
    assert (NP_MAT_NOTE in result.notes) == (not had_mat)
    assert hasattr(np, "mat") == had_mat  # numpy is as it was after the run


def test_differential_drive_barrier_and_plotting_on_r_axes():
    result = run_experiment(DATA / "dd_barriers_with_plotting.py", duration=CAP, seed=1)
    _finished(result)
    assert NP_MAT_NOTE not in result.notes  # this script never used np.mat


def test_backwards_map_backs_off_and_turns_the_front_towards_a_target_behind():
    with rps_aliases():
        from rps.utilities.transformations import create_si_to_uni_dynamics_with_backwards_motion

        f = create_si_to_uni_dynamics_with_backwards_motion()
    poses = np.zeros((3, 3))
    # robot 0: target behind and a little left; robot 1: ahead; robot 2: no command
    dxu = f(np.array([[-0.1, 0.1, 0.0], [0.01, 0.01, 0.0]]), poses)
    assert dxu[0, 0] < 0 < dxu[0, 1]
    assert dxu[1, 0] > 3.0  # atan2 near ±π: a fast turn (atan would give ω ≈ −0.3 rad/s)
    assert dxu[0, 2] == 0.0 and dxu[1, 2] == 0.0  # a zero command neither drives nor turns


def test_differential_drive_certificate_keeps_wheels_within_limits_and_robots_apart():
    with rps_aliases():
        from rps.utilities.barrier_certificates import create_unicycle_differential_drive_barrier_certificate

        f = create_unicycle_differential_drive_barrier_certificate(wheel_vel_limit=12.5)
    x = np.array([[-0.1, 0.1], [0.0, 0.0], [0.0, np.pi]])  # head-on, 0.2 m apart
    dxu = np.array([[0.2, 0.2], [0.0, 0.0]])
    keep = dxu.copy()
    safe = f(dxu, x)
    assert np.array_equal(dxu, keep)
    r, L = 0.016, 0.105
    wheels = np.abs(np.vstack(((2 * safe[0] + L * safe[1]) / (2 * r), (2 * safe[0] - L * safe[1]) / (2 * r))))
    assert wheels.max() <= 12.5 + 1e-9
    assert safe[0, 0] < 0.2 and safe[0, 1] < 0.2  # the filter slowed the head-on approach
    obstacle = f(np.array([[0.2], [0.0]]), np.array([[0.0], [0.0], [0.0]]), np.array([[0.19], [0.03]]))
    assert obstacle[0, 0] < 0.2
    with pytest.raises(ValueError, match="disturbance"):
        with rps_aliases():
            from rps.utilities.barrier_certificates import (
                create_unicycle_differential_drive_barrier_certificate as make,
            )

            make(disturbance=float("nan"))


def test_robotarium_has_rps_constants_and_a_headless_figure():
    with rps_aliases():
        import rps.robotarium as robotarium
        from rps.utilities import misc

        r = robotarium.Robotarium(number_of_robots=2, show_figure=True, sim_in_real_time=False)
        assert misc.plt.get_backend().lower() == "agg"
        assert "plt" in misc.__all__ and "np" in misc.__all__
    assert r.robot_diameter == 0.11 and r.wheel_radius == 0.016 and r.base_length == 0.105
    assert r.max_linear_velocity == 0.2 and r.max_wheel_velocity == 12.5
    assert r.axes.figure is r.figure
    x0, x1 = r.axes.get_xlim()
    assert x0 < -1.6 and x1 > 1.6
