"""Go-to-goal controllers at the unicycle and single-integrator levels.

Vectorised, non-mutating versions of the rps controllers
(``rps.utilities.controllers``; REFERENCE.md §2), without rps's defects: no
division by zero at α = 0 in the pose controller, per-controller state held in
an object rather than a closure variable shared between calls, and no in-place
changes of caller arrays. Shapes: poses ``(N, 3)``, positions ``(N, 2)``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.kinematics import saturate, si_to_unicycle
from swarmdeck.devices.gritsbot import wrap_angle

FloatArray = NDArray[np.float64]


def si_position_controller(
    positions: ArrayLike, goals: ArrayLike, gain: float = 1.0, speed_limit: float = 0.15
) -> FloatArray:
    """Single-integrator go-to-goal: u = gain·(goal − p), norm limited to ``speed_limit`` m/s.

    rps ``create_si_position_controller`` (x/y gains 1, magnitude limit 0.15).
    """
    positions = np.asarray(positions, dtype=float)
    goals = np.asarray(goals, dtype=float)
    return saturate(gain * (goals - positions), speed_limit)


def clf_unicycle_position_controller(
    poses: ArrayLike, goals: ArrayLike, linear_gain: float = 0.8, angular_gain: float = 3.0
) -> tuple[FloatArray, FloatArray]:
    """Control-Lyapunov unicycle controller to a position (rps ``create_clf_unicycle_position_controller``).

    With e = goal − p, ρ = ‖e‖ and α = atan2(e) − θ: v = k_v ρ cos α, ω = k_ω ρ sin α.
    """
    poses = np.asarray(poses, dtype=float)
    goals = np.asarray(goals, dtype=float)
    e = goals[:, :2] - poses[:, :2]
    rho = np.linalg.norm(e, axis=1)
    alpha = np.arctan2(e[:, 1], e[:, 0]) - poses[:, 2]
    return linear_gain * rho * np.cos(alpha), angular_gain * rho * np.sin(alpha)


def clf_unicycle_pose_controller(
    poses: ArrayLike,
    goals: ArrayLike,
    approach_angle_gain: float = 1.0,
    desired_angle_gain: float = 2.7,
    rotation_error_gain: float = 1.0,
    near_goal: float = 1e-3,
) -> tuple[FloatArray, FloatArray]:
    """Pose (position and heading) controller in polar coordinates (rps ``create_clf_unicycle_pose_controller``).

    In the goal frame: e = ‖R(−θ_g)(p_g − p)‖, ϑ = atan2 of that vector,
    α = wrap(ϑ − (θ − θ_g)); v = γ e cos α, ω = k α + γ (cos α · sin α/α)(α + h ϑ).
    sin α/α is evaluated as ``np.sinc(α/π)`` so α = 0 is well defined (rps divides by zero),
    and within ``near_goal`` m of the goal only the heading is corrected (ω = k·(θ_g − θ)).
    """
    poses = np.asarray(poses, dtype=float)
    goals = np.asarray(goals, dtype=float)
    d = goals[:, :2] - poses[:, :2]
    cg, sg = np.cos(goals[:, 2]), np.sin(goals[:, 2])
    tx = cg * d[:, 0] + sg * d[:, 1]
    ty = -sg * d[:, 0] + cg * d[:, 1]
    e = np.hypot(tx, ty)
    theta = np.arctan2(ty, tx)
    alpha = wrap_angle(theta - (poses[:, 2] - goals[:, 2]))
    ca = np.cos(alpha)
    sinc = np.sinc(alpha / np.pi)
    g, k, h = approach_angle_gain, desired_angle_gain, rotation_error_gain
    v = g * e * ca
    w = k * alpha + g * ca * sinc * (alpha + h * theta)
    # At the goal the polar angle ϑ is undefined and flips by ±π on round-off, which
    # makes rps's controller spin a parked robot; there, only the heading is corrected.
    near = e < near_goal
    v = np.where(near, 0.0, v)
    w = np.where(near, k * wrap_angle(goals[:, 2] - poses[:, 2]), w)
    return v, w


@dataclass
class HybridPoseController:
    """Drive to a position through the look-ahead point, then turn in place to the heading.

    rps ``create_hybrid_unicycle_pose_controller``, vectorised, with its
    per-robot approach/turn state kept on the object (hysteresis: a robot
    re-enters the approach phase if pushed farther than ``position_error``).

    Attributes:
        speed_limit: look-ahead point speed during approach, m/s.
        angular_gain: ω = gain · heading error while turning, 1/s.
        position_error: approach ends within this distance, m.
        position_epsilon: hysteresis band, m.
        rotation_error: turning ends within this heading error, rad.
        lookahead: ℓ, m.
        gain: look-ahead point velocity per m of position error, 1/s (rps: 1).
    """

    speed_limit: float = 0.15
    angular_gain: float = 2.0
    position_error: float = 0.03
    position_epsilon: float = 0.01
    rotation_error: float = 0.05
    lookahead: float = 0.03
    gain: float = 1.0
    _approach: NDArray[np.bool_] | None = field(default=None, repr=False)

    def reset(self) -> None:
        """Forget the phase of every robot (call when goals change)."""
        self._approach = None

    def __call__(self, poses: ArrayLike, goals: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """``(v, ω)`` ``(N,)`` each for goal poses ``(N, 3)``."""
        poses = np.asarray(poses, dtype=float)
        goals = np.asarray(goals, dtype=float)
        n = poses.shape[0]
        if self._approach is None or self._approach.shape != (n,):
            self._approach = np.ones(n, dtype=bool)
        # Position error of the robot centre; the approach steers its look-ahead point to the goal.
        dist = np.linalg.norm(goals[:, :2] - poses[:, :2], axis=1)
        heading_err = wrap_angle(goals[:, 2] - poses[:, 2])
        approach = self._approach & (dist > self.position_error - self.position_epsilon)
        approach |= dist > self.position_error + self.position_epsilon
        turn = ~approach & (np.abs(heading_err) > self.rotation_error)
        # As in rps: the centre's position error is used as the look-ahead point's velocity,
        # whose equilibrium puts the centre (not the look-ahead point) on the goal.
        u = saturate(self.gain * (goals[:, :2] - poses[:, :2]), self.speed_limit)
        v_app, w_app = si_to_unicycle(poses, u, self.lookahead)
        v = np.where(approach, v_app, 0.0)
        w = np.where(approach, w_app, np.where(turn, self.angular_gain * heading_err, 0.0))
        self._approach = approach
        return v, w


def at_pose(poses: ArrayLike, goals: ArrayLike, position_error: float = 0.05, rotation_error: float = 0.2) -> NDArray[np.bool_]:
    """``(N,)`` mask of robots within ``position_error`` m and ``rotation_error`` rad of their goal pose."""
    poses = np.asarray(poses, dtype=float)
    goals = np.asarray(goals, dtype=float)
    d = np.linalg.norm(goals[:, :2] - poses[:, :2], axis=1)
    return (d <= position_error) & (np.abs(wrap_angle(goals[:, 2] - poses[:, 2])) <= rotation_error)


def at_position(positions: ArrayLike, goals: ArrayLike, position_error: float = 0.02) -> NDArray[np.bool_]:
    """``(N,)`` mask of points within ``position_error`` m of their goal."""
    positions = np.asarray(positions, dtype=float)
    goals = np.asarray(goals, dtype=float)
    return np.linalg.norm(goals[:, :2] - positions[:, :2], axis=1) <= position_error
