"""The GRITSBot: physical constants, wheel kinematics and the exact unicycle step.

Constants are the Robotarium defaults of REFERENCE.md §1. All functions are pure
and vectorised over robots: ``v`` and ``w`` are ``(N,)`` arrays, poses ``(N, 3)``
rows ``[x, y, θ]`` in metres and radians.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.checks import require_positive

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class GritsBotParams:
    """Physical parameters of one GRITSBot (REFERENCE.md §1).

    Attributes:
        diameter: body diameter, m.
        wheel_radius: r, m.
        axle_length: L, distance between the wheels, m.
        max_speed: largest linear speed, m/s (= r · max_wheel_speed).
        max_wheel_speed: largest wheel angular speed, rad/s.
        lookahead: ℓ of the look-ahead (near-identity) diffeomorphism, m.
    """

    diameter: float = 0.11
    wheel_radius: float = 0.016
    axle_length: float = 0.105
    max_speed: float = 0.2
    max_wheel_speed: float = 12.5
    lookahead: float = 0.03

    def __post_init__(self) -> None:
        require_positive(self, ("diameter", "wheel_radius", "axle_length", "max_speed", "max_wheel_speed", "lookahead"))

    @property
    def radius(self) -> float:
        """Body radius, m."""
        return self.diameter / 2.0

    @property
    def max_angular_speed(self) -> float:
        """Largest turning rate in place, rad/s: ω = 2 r ω_max / L."""
        return 2.0 * self.wheel_radius * self.max_wheel_speed / self.axle_length


def unicycle_to_wheels(v: ArrayLike, w: ArrayLike, params: GritsBotParams) -> tuple[FloatArray, FloatArray]:
    """Wheel speeds (ω_R, ω_L) in rad/s from (v, ω): ω_R,L = (2v ± ωL) / (2r)."""
    v = np.asarray(v, dtype=float)
    w = np.asarray(w, dtype=float)
    r, L = params.wheel_radius, params.axle_length
    return (2.0 * v + w * L) / (2.0 * r), (2.0 * v - w * L) / (2.0 * r)


def wheels_to_unicycle(right: ArrayLike, left: ArrayLike, params: GritsBotParams) -> tuple[FloatArray, FloatArray]:
    """(v, ω) from wheel speeds: v = r(ω_R + ω_L)/2, ω = r(ω_R − ω_L)/L."""
    right = np.asarray(right, dtype=float)
    left = np.asarray(left, dtype=float)
    r, L = params.wheel_radius, params.axle_length
    return r * (right + left) / 2.0, r * (right - left) / L


def wheel_scale(v: ArrayLike, w: ArrayLike, params: GritsBotParams) -> FloatArray:
    """Per-robot factor s ∈ (0, 1] that brings both wheels within ±max_wheel_speed.

    Scaling v and ω by the same s keeps the commanded curvature ω/v (unlike rps,
    which clips each wheel on its own and so changes the direction of motion).
    Peaks within 1e-12 (relative) of the limit count as within it, so limiting an
    already limited command changes nothing (the console, the transport backend and
    the simulated robots may each apply the limits).
    """
    right, left = unicycle_to_wheels(v, w, params)
    peak = np.maximum(np.abs(right), np.abs(left))
    over = peak > params.max_wheel_speed * (1.0 + 1e-12)
    return np.divide(params.max_wheel_speed, peak, out=np.ones_like(peak), where=over)


def limit_unicycle(v: ArrayLike, w: ArrayLike, params: GritsBotParams) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """Apply the wheel limits by one uniform scale per robot.

    Returns the limited ``(v, w)`` (new arrays) and a boolean ``(N,)`` mask of the
    robots whose command was scaled down (actuator saturation).
    """
    v = np.asarray(v, dtype=float)
    w = np.asarray(w, dtype=float)
    s = wheel_scale(v, w, params)
    return v * s, w * s, s < 1.0


def unicycle_step(poses: ArrayLike, v: ArrayLike, w: ArrayLike, dt: float) -> FloatArray:
    """Integrate ẋ = v cos θ, ẏ = v sin θ, θ̇ = ω exactly over ``dt`` with constant (v, ω).

    The robot moves on a circular arc of radius v/ω; for |ω·dt| small the
    straight-line limit is used through the series of sin(a)/a and (1−cos a)/a,
    so the result is smooth in ω. Heading is wrapped to (−π, π].

    Args:
        poses: ``(N, 3)`` rows ``[x, y, θ]``.
        v: ``(N,)`` linear speeds, m/s.
        w: ``(N,)`` angular speeds, rad/s.
        dt: step, s.

    Returns:
        New ``(N, 3)`` array.
    """
    poses = np.asarray(poses, dtype=float)
    v = np.asarray(v, dtype=float)
    w = np.asarray(w, dtype=float)
    theta = poses[:, 2]
    a = w * dt  # heading change over the step
    small = np.abs(a) < 1e-6
    a_safe = np.where(small, 1.0, a)
    # f = sin(a)/a, g = (1 - cos a)/a with their Taylor series near 0.
    f = np.where(small, 1.0 - a * a / 6.0, np.sin(a_safe) / a_safe)
    g = np.where(small, a / 2.0 - a**3 / 24.0, (1.0 - np.cos(a_safe)) / a_safe)
    d = v * dt
    c, s = np.cos(theta), np.sin(theta)
    out = np.empty_like(poses)
    out[:, 0] = poses[:, 0] + d * (f * c - g * s)
    out[:, 1] = poses[:, 1] + d * (f * s + g * c)
    out[:, 2] = wrap_angle(theta + a)
    return out


def wrap_angle(theta: ArrayLike) -> FloatArray:
    """Wrap angles to (−π, π]."""
    theta = np.asarray(theta, dtype=float)
    return np.arctan2(np.sin(theta), np.cos(theta))
