"""rps.utilities.controllers on swarmdeck's vectorised controllers, in rps's column layout."""
from __future__ import annotations

import numpy as np

from swarmdeck.core.constants import AXLE_LENGTH, WHEEL_RADIUS
from swarmdeck.devices.controllers import (
    HybridPoseController,
    at_pose,
    clf_unicycle_pose_controller,
    clf_unicycle_position_controller,
)
from swarmdeck.devices.rps.utilities.transformations import *  # noqa: F401,F403 - rps's module re-exports them  # noqa: F401,F403 - rps's module re-exports them
from swarmdeck.devices.rps.utilities.transformations import __all__ as _TRANSFORMATIONS
from swarmdeck.devices.rps.utilities.transformations import create_si_to_uni_mapping as _si_to_uni_mapping


def create_si_position_controller(x_velocity_gain: float = 1, y_velocity_gain: float = 1, velocity_magnitude_limit: float = 0.15):
    """f(xi (2, N), positions (2, N)) → (2, N): gains·(goal − x), norm-limited."""
    gains = np.array([[x_velocity_gain], [y_velocity_gain]], dtype=float)

    def si_position_controller(xi, positions):
        dxi = gains * (np.asarray(positions, dtype=float) - np.asarray(xi, dtype=float))
        norms = np.linalg.norm(dxi, axis=0)
        scale = np.where(norms > velocity_magnitude_limit, velocity_magnitude_limit / np.maximum(norms, 1e-300), 1.0)
        return dxi * scale

    return si_position_controller


def create_clf_unicycle_position_controller(linear_velocity_gain: float = 0.8, angular_velocity_gain: float = 3):
    """f(states (3, N), positions (2, N)) → (2, N) [v; ω]."""

    def position_uni_clf_controller(states, positions):
        v, w = clf_unicycle_position_controller(np.asarray(states, dtype=float).T, np.asarray(positions, dtype=float).T,
                                                linear_velocity_gain, angular_velocity_gain)
        return np.vstack((v, w))

    return position_uni_clf_controller


def create_clf_unicycle_pose_controller(approach_angle_gain: float = 1, desired_angle_gain: float = 2.7, rotation_error_gain: float = 1):
    """f(states (3, N), poses (3, N)) → (2, N) [v; ω]."""

    def pose_uni_clf_controller(states, poses):
        v, w = clf_unicycle_pose_controller(np.asarray(states, dtype=float).T, np.asarray(poses, dtype=float).T,
                                            approach_angle_gain, desired_angle_gain, rotation_error_gain)
        return np.vstack((v, w))

    return pose_uni_clf_controller


def create_hybrid_unicycle_pose_controller(linear_velocity_gain: float = 1, angular_velocity_gain: float = 2,
                                           velocity_magnitude_limit: float = 0.15, angular_velocity_limit: float = np.pi,
                                           position_error: float = 0.05, position_epsilon: float = 0.02,
                                           rotation_error: float = 0.05):
    """f(states (3, N), poses (3, N)) → (2, N): approach, then turn in place (state kept per controller)."""
    ctrl = HybridPoseController(speed_limit=velocity_magnitude_limit, angular_gain=angular_velocity_gain,
                                position_error=position_error, position_epsilon=position_epsilon,
                                rotation_error=rotation_error, lookahead=0.05)

    def hybrid_pose_controller(states, poses):
        v, w = ctrl(np.asarray(states, dtype=float).T, np.asarray(poses, dtype=float).T)
        return np.vstack((linear_velocity_gain * v, np.clip(w, -angular_velocity_limit, angular_velocity_limit)))

    return hybrid_pose_controller


# rps 2.0's names (rps/utilities/controllers.py on `master`), with its defaults
def create_uni_position_controller(x_velocity_gain: float = 0.8, y_velocity_gain: float = 0.8,
                                   velocity_magnitude_limit: float = 0.15, projection_distance: float = 0.03):
    """rps 2.0: f(states (3, N), positions (2, N)) → (2, N) [v; ω]: the single-integrator controller on
    the look-ahead points, mapped to the unicycle."""
    si = create_si_position_controller(x_velocity_gain, y_velocity_gain, velocity_magnitude_limit)
    si_to_uni, uni_to_si_states = _si_to_uni_mapping(projection_distance)

    def position_controller_uni(states, poses):
        return si_to_uni(si(uni_to_si_states(states), np.asarray(poses, dtype=float)[:2]), states)

    return position_controller_uni


def create_pose_controller_clf(approach_angle_gain: float = 1, desired_angle_gain: float = 2.7,
                               rotation_error_gain: float = 1, **_limits):
    """rps 2.0's name for :func:`create_clf_unicycle_pose_controller` (its limit keywords are the
    robot's own here: the wheel limits apply in any case)."""
    return create_clf_unicycle_pose_controller(approach_angle_gain, desired_angle_gain, rotation_error_gain)


def create_pose_controller_hybrid(linear_velocity_gain: float = 0.8, angular_velocity_limit: float = np.pi,
                                  position_error: float = 0.05, position_epsilon: float = 0.02,
                                  rotation_error: float = 0.05, velocity_magnitude_limit: float = 0.15, **_unused):
    """rps 2.0's name for :func:`create_hybrid_unicycle_pose_controller`: f(states, poses) → (2, N)."""
    inner = create_hybrid_unicycle_pose_controller(linear_velocity_gain=linear_velocity_gain,
                                                   velocity_magnitude_limit=velocity_magnitude_limit,
                                                   angular_velocity_limit=angular_velocity_limit,
                                                   position_error=position_error, position_epsilon=position_epsilon,
                                                   rotation_error=rotation_error)

    def controller_hybrid(states, poses, in_approach_state=None):
        return inner(states, poses)

    return controller_hybrid


def _parking(controller, position_error: float, rotation_error: float):
    """``controller`` with zero commands for the robots already at their goal pose (rps 2.0's parking)."""
    def parked(states, poses):
        dxu = np.asarray(controller(states, poses), dtype=float)
        done = at_pose(np.asarray(states, dtype=float).T, np.asarray(poses, dtype=float).T, position_error,
                       rotation_error)
        return np.where(done[None, :], 0.0, dxu)

    return parked


def create_pose_parking_controller_clf(approach_angle_gain: float = 1, desired_angle_gain: float = 2.7,
                                       rotation_error_gain: float = 1, wheel_velocity_limit: float = 10.0,
                                       wheel_radius: float = WHEEL_RADIUS, base_length: float = AXLE_LENGTH,
                                       position_error: float = 0.05, rotation_error: float = 0.2):
    """rps 2.0: :func:`create_pose_controller_clf` that stops the robots at their goal pose."""
    return _parking(create_pose_controller_clf(approach_angle_gain, desired_angle_gain, rotation_error_gain),
                    position_error, rotation_error)


def create_pose_parking_controller_hybrid(linear_velocity_gain: float = 0.8, angular_velocity_limit: float = np.pi,
                                          position_error: float = 0.05, position_epsilon: float = 0.02,
                                          rotation_error: float = 0.05, velocity_magnitude_limit: float = 0.15,
                                          **_unused):
    """rps 2.0: :func:`create_pose_controller_hybrid` that stops the robots at their goal pose."""
    inner = create_pose_controller_hybrid(linear_velocity_gain, angular_velocity_limit, position_error,
                                          position_epsilon, rotation_error, velocity_magnitude_limit)
    return _parking(lambda states, poses: inner(states, poses), position_error, rotation_error)


__all__ = [
    "create_clf_unicycle_pose_controller", "create_pose_parking_controller_clf", "create_pose_parking_controller_hybrid", "create_clf_unicycle_position_controller",
    "create_hybrid_unicycle_pose_controller", "create_pose_controller_clf", "create_pose_controller_hybrid",
    "create_si_position_controller", "create_uni_position_controller", *_TRANSFORMATIONS,
]
