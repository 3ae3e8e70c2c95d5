"""The rps facade has the public names of both rps generations, and the private ones real code reaches for
(robotarium/robotarium_python_simulator: rps 1.x on `dev`, 6bb184e and later; rps 2.0 on `master`)."""
import numpy as np
import pytest

from swarmdeck.devices.rps import rps_aliases

MODULES = {  # module: names defined there in rps 1.x and 2.0 (their `def`s; star imports hand on the transformations)
    "rps.utilities.barrier_certificates": [
        "create_single_integrator_barrier_certificate", "create_single_integrator_barrier_certificate_with_boundary",
        "create_single_integrator_barrier_certificate2", "create_unicycle_barrier_certificate",
        "create_unicycle_barrier_certificate_with_boundary", "create_unicycle_barrier_certificate2",
        "create_unicycle_differential_drive_barrier_certificate",
        "create_unicycle_differential_drive_barrier_certificate_with_boundary",
        "create_si_barrier_certificate", "create_si_barrier_certificate_with_boundary",
        "create_uni_barrier_certificate", "create_uni_barrier_certificate_with_boundary",
        "create_si_to_uni_mapping", "create_si_to_uni_dynamics", "np"],
    "rps.utilities.barrier_certificates2": ["create_robust_barriers"],
    "rps.utilities.controllers": [
        "create_si_position_controller", "create_clf_unicycle_position_controller",
        "create_clf_unicycle_pose_controller", "create_hybrid_unicycle_pose_controller",
        "create_uni_position_controller", "create_pose_controller_clf", "create_pose_controller_hybrid",
        "create_pose_parking_controller_clf", "create_pose_parking_controller_hybrid",
        "create_si_to_uni_mapping", "create_si_to_uni_dynamics", "create_si_to_uni_dynamics_with_backwards_motion",
        "create_uni_to_si_dynamics", "np"],
    "rps.utilities.graph": ["cycle_GL", "cycleGL", "lineGL", "completeGL", "random_connectedGL", "randomGL",
                            "topological_neighbors", "delta_disk_neighbors"],
    "rps.utilities.misc": ["generate_initial_conditions", "at_pose", "at_position", "determine_marker_size",
                           "determine_font_size", "generate_initial_poses", "generate_random_poses",
                           "generate_random_positions", "create_at_pose", "create_at_position", "rotation_matrix",
                           "unique_filename", "np", "plt"],
    "rps.utilities.transformations": ["create_si_to_uni_dynamics", "create_si_to_uni_dynamics_with_backwards_motion",
                                      "create_si_to_uni_mapping", "create_uni_to_si_dynamics",
                                      "create_uni_to_si_mapping", "np"],
}
ROBOTARIUM = [  # rps 1.x and 2.0 attributes, public and the private ones scripts use (MARBLER: _errors)
    "get_poses", "set_velocities", "step", "call_at_scripts_end", "debug", "figure", "axes", "_axes_handle",
    "poses", "velocities", "boundaries", "BOUNDARIES", "time_step", "TIME_STEP", "number_of_robots", "show_figure",
    "initial_conditions", "robot_diameter", "robot_radius", "wheel_radius", "base_length", "max_linear_velocity",
    "max_angular_velocity", "max_wheel_velocity", "robot_length", "robot_width", "collision_offset",
    "collision_diameter", "ROBOT_DIAMETER", "WHEEL_RADIUS", "BASE_LENGTH", "MAX_LINEAR_VELOCITY",
    "MAX_WHEEL_VELOCITY", "MAX_ANGULAR_VELOCITY", "COLLISION_OFFSET", "COLLISION_DIAMETER", "robot_colormap",
    "get_distances", "get_encoders", "_errors", "_validate", "_threshold", "_uni_to_diff", "_diff_to_uni",
    "_iterations", "_iteration", "_called_step_already", "_checked_poses_already", "initializing",
]


@pytest.mark.parametrize("module", sorted(MODULES))
def test_every_rps_name_is_there_and_star_import_hands_it_on(module):
    with rps_aliases():
        namespace: dict = {}
        exec(f"from {module} import *", namespace)  # noqa: S102 - how rps scripts import them
        missing = [n for n in MODULES[module] if n not in namespace]
    assert not missing, f"{module} lacks {missing}"


def test_robotarium_has_both_generations_attributes():
    with rps_aliases():
        import rps.robotarium

        r = rps.robotarium.Robotarium(number_of_robots=3, show_figure=False, sim_in_real_time=False)
    assert [a for a in ROBOTARIUM if not hasattr(r, a)] == []


def test_private_helpers_compute_as_rps_does():
    from swarmdeck.devices.rps.robotarium import Robotarium

    r = Robotarium(number_of_robots=2, sim_in_real_time=False)
    dxu = np.array([[0.1, -0.05], [1.0, 0.0]])
    dxdd = r._uni_to_diff(dxu)  # rps: rows (2v − Lω)/(2r), (2v + Lω)/(2r)
    np.testing.assert_allclose(dxdd, [[(0.2 - 0.105) / 0.032, -0.1 / 0.032], [(0.2 + 0.105) / 0.032, -0.1 / 0.032]])
    np.testing.assert_allclose(r._diff_to_uni(dxdd), dxu)
    fast = r._threshold(np.array([[0.3], [0.0]]))
    assert fast[0, 0] == pytest.approx(0.2) and fast[1, 0] == 0.0  # within the wheel limits
    assert r._validate() == {} and r._errors == {}


def test_star_imported_2x_helpers_work():
    with rps_aliases():
        from rps.utilities.barrier_certificates import create_si_barrier_certificate_with_boundary
        from rps.utilities.controllers import create_si_to_uni_mapping, create_uni_position_controller
        from rps.utilities.misc import create_at_pose, generate_initial_poses

        poses = np.array([[0.0, 0.3], [0.0, 0.0], [0.0, 0.0]])
        si = create_si_barrier_certificate_with_boundary()(np.array([[0.2, -0.2], [0.0, 0.0]]), poses[:2])
        assert si[0, 0] < 0.2
        dxu = create_uni_position_controller()(poses, np.array([[0.5, 0.3], [0.0, 0.5]]))
        assert dxu.shape == (2, 2) and dxu[0, 0] > 0
        done, there = create_at_pose()(poses, poses)  # rps 2.x: a (N,) bool mask, not 1.x's indices
        assert done is True and there.dtype == bool and there.tolist() == [True, True]
        assert generate_initial_poses(4).shape == (3, 4)
        si_to_uni, uni_to_si = create_si_to_uni_mapping()
        assert uni_to_si(poses).shape == (2, 2)
