"""rps.utilities.controllers on swarmdeck's vectorised controllers, in rps's column layout."""
from __future__ import annotations

import numpy as np

from swarmdeck.devices.controllers import (
    HybridPoseController,
    clf_unicycle_pose_controller,
    clf_unicycle_position_controller,
)


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
