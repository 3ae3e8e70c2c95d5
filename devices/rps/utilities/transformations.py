"""rps.utilities.transformations: single integrator ↔ unicycle, in rps's (2, N) / (3, N) columns."""
from __future__ import annotations

import numpy as np

from swarmdeck.core.kinematics import lookahead_points, si_to_unicycle, unicycle_to_si


def _heading_map(dxi, poses, linear_velocity_gain: float, angular_velocity_limit: float) -> np.ndarray:
    """rps's heading-based single-integrator → unicycle map, (2, N) from dxi (2, N) at poses (3, N).

    v = k (cos θ u_x + sin θ u_y); with u_⊥ = −sin θ u_x + cos θ u_y, ω = ω_max·(2/π)·atan2(u_⊥, v).
    """
    dxi = np.asarray(dxi, dtype=float)
    poses = np.asarray(poses, dtype=float)
    a = np.cos(poses[2])
    b = np.sin(poses[2])
    dxu = np.zeros((2, dxi.shape[1]))
    # "+ 0.0" turns −0.0 into +0.0: a zero command must give ω = 0, not atan2(0, −0) = π
    dxu[0] = linear_velocity_gain * (a * dxi[0] + b * dxi[1]) + 0.0
    perp = -b * dxi[0] + a * dxi[1] + 0.0
    dxu[1] = angular_velocity_limit * np.arctan2(perp, dxu[0]) / (np.pi / 2)
    return dxu


def create_si_to_uni_dynamics(linear_velocity_gain: float = 1, angular_velocity_limit: float = np.pi):
    """rps's heading-based map: v = k‖u‖cos φ, ω = ω_max·2/π·atan2(sin φ, cos φ) (φ: angle of u to θ)."""

    def si_to_uni_dyn(dxi, poses):
        return _heading_map(dxi, poses, linear_velocity_gain, angular_velocity_limit)

    return si_to_uni_dyn


def create_si_to_uni_dynamics_with_backwards_motion(linear_velocity_gain: float = 1, angular_velocity_limit: float = np.pi):
    """rps's "backwards motion" map, which is rps's heading map: v = k (cos θ u_x + sin θ u_y) is
    negative when u points behind the robot (it backs off) while ω = ω_max·(2/π)·atan2(u_⊥, v) turns
    the front towards u. An ``atan(u_⊥ / v)`` version turns far less when v is small and left robots
    hovering ~6 cm from their goals (rps's own ``si_go_to_point.py`` never finished under swarmdeck).
    """
    return create_si_to_uni_dynamics(linear_velocity_gain, angular_velocity_limit)


def create_si_to_uni_mapping(projection_distance: float = 0.05, angular_velocity_limit: float = np.pi):
    """The look-ahead diffeomorphism: returns (si_to_uni_dyn(dxi, poses), uni_to_si_states(poses))."""

    def si_to_uni_dyn(dxi, poses):
        poses = np.asarray(poses, dtype=float).T
        v, w = si_to_unicycle(poses, np.asarray(dxi, dtype=float).T, projection_distance)
        return np.vstack((v, np.clip(w, -angular_velocity_limit, angular_velocity_limit)))

    def uni_to_si_states(poses):
        return lookahead_points(np.asarray(poses, dtype=float).T, projection_distance).T

    return si_to_uni_dyn, uni_to_si_states


def create_uni_to_si_dynamics(projection_distance: float = 0.05):
    """Look-ahead point velocity (2, N) of unicycle commands dxu (2, N) at poses (3, N)."""

    def uni_to_si_dyn(dxu, poses):
        dxu = np.asarray(dxu, dtype=float)
        return unicycle_to_si(np.asarray(poses, dtype=float).T, dxu[0], dxu[1], projection_distance).T

    return uni_to_si_dyn


def create_uni_to_si_mapping(projection_distance: float = 0.05):
    """rps 2.0: returns (uni_to_si_dyn(dxu (2, N), states (3, N)) → dxi (2, N),
    si_to_uni_states(uni_states (3, N), si_states (2, N)) → the centres (2, N) behind the look-ahead points)."""
    if not (np.isfinite(projection_distance) and projection_distance > 0):
        raise ValueError(f"projection_distance must be a positive number, got {projection_distance!r}")
    d = float(projection_distance)

    def uni_to_si(dxu, states):
        return create_uni_to_si_dynamics(d)(dxu, states)

    def si_to_uni(uni_states, si_states):
        theta = np.asarray(uni_states, dtype=float)[2]
        return np.asarray(si_states, dtype=float)[:2] - d * np.vstack((np.cos(theta), np.sin(theta)))

    return uni_to_si, si_to_uni


# rps's module does `import numpy as np`, and `from rps.utilities.transformations import *` hands it on
__all__ = [
    "create_si_to_uni_dynamics", "create_si_to_uni_dynamics_with_backwards_motion", "create_si_to_uni_mapping",
    "create_uni_to_si_dynamics", "create_uni_to_si_mapping", "np",
]
