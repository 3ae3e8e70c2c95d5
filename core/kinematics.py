"""The robot model shared by everyone: constants, the look-ahead map, the wheel map, speed limits.

Defined once, at the bottom of the dependency graph (``safety``, ``devices``,
``console`` and ``tracking`` all use it; it imports no other swarmdeck package).

* :class:`UnicycleParams` — a differential-drive robot (wheel radius r, axle
  length L, wheel speed limit, look-ahead ℓ); :class:`GritsBotParams` adds the
  GRITSBot's body (REFERENCE.md §1). The barrier filter takes either.
* The look-ahead (near-identity) diffeomorphism, Olfati-Saber's construction
  (REFERENCE.md §1): the point ``p = (x + ℓ cos θ, y + ℓ sin θ)`` of a unicycle
  moves as ``ṗ = M(θ) [v, ω]ᵀ`` with ``M = [[cos θ, −ℓ sin θ], [sin θ, ℓ cos θ]]``,
  invertible for ℓ > 0, so a single-integrator velocity for ``p`` maps exactly
  to one unicycle command.
* The wheel map ω_R,L = (2v ± Lω)/(2r) and its inverse, and the wheel limits
  applied by one uniform scale per robot (keeps the curvature ω/v).
* :func:`saturate`: single-integrator speed limit per robot; non-finite rows
  become zero (the safe reading of a NaN command).
* :func:`unicycle_step`: the exact unicycle motion over one step (the simulator's, the firmware
  model's, the predictions'); :func:`wrap_angle` to (−π, π].

Shapes: poses ``(N, 3)`` rows ``[x, y, θ]`` (m, rad); velocities ``(N, 2)`` m/s;
``v`` (N,) m/s, ``ω`` (N,) rad/s. All functions are pure and return new arrays.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.checks import require_positive
from swarmdeck.core.constants import (
    AXLE_LENGTH,
    LOOKAHEAD,
    MAX_LINEAR_SPEED,
    MAX_WHEEL_SPEED,
    ROBOT_DIAMETER,
    WHEEL_RADIUS,
)

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class UnicycleParams:
    """A differential-drive robot (defaults: the GRITSBot, REFERENCE.md §1).

    Attributes:
        wheel_radius: r, m.
        axle_length: L, distance between the wheels, m.
        max_wheel_speed: largest wheel angular speed, rad/s.
        lookahead: ℓ of the look-ahead (near-identity) diffeomorphism, m.
    """

    wheel_radius: float = WHEEL_RADIUS
    axle_length: float = AXLE_LENGTH
    max_wheel_speed: float = MAX_WHEEL_SPEED
    lookahead: float = LOOKAHEAD

    def __post_init__(self) -> None:
        require_positive(self, ("wheel_radius", "axle_length", "max_wheel_speed", "lookahead"))

    @property
    def max_linear_speed(self) -> float:
        """Forward speed with both wheels at the limit, m/s: r · ω_max (0.2 for the GRITSBot)."""
        return self.wheel_radius * self.max_wheel_speed

    @property
    def max_angular_speed(self) -> float:
        """Largest turning rate in place, rad/s: ω = 2 r ω_max / L."""
        return 2.0 * self.wheel_radius * self.max_wheel_speed / self.axle_length


@dataclass(frozen=True)
class GritsBotParams(UnicycleParams):
    """One GRITSBot (REFERENCE.md §1): the drive of :class:`UnicycleParams` plus its body.

    Attributes:
        diameter: body diameter, m.
        max_speed: largest linear speed the experiment API commands, m/s (= r · max_wheel_speed).
    """

    diameter: float = ROBOT_DIAMETER
    max_speed: float = MAX_LINEAR_SPEED

    def __post_init__(self) -> None:
        require_positive(self, ("diameter", "wheel_radius", "axle_length", "max_speed", "max_wheel_speed", "lookahead"))

    @property
    def radius(self) -> float:
        """Body radius, m."""
        return self.diameter / 2.0


# ---------------------------------------------------------------------------- the look-ahead map
def lookahead_points(poses: ArrayLike, ell: float) -> FloatArray:
    """Look-ahead points ``(N, 2)`` of poses ``(N, 3)``, m: p = (x + ℓ cos θ, y + ℓ sin θ)."""
    poses = np.asarray(poses, dtype=float)
    th = poses[:, 2]
    return np.column_stack((poses[:, 0] + ell * np.cos(th), poses[:, 1] + ell * np.sin(th)))


def si_to_unicycle(poses: ArrayLike, u: ArrayLike, ell: float) -> tuple[FloatArray, FloatArray]:
    """Unicycle ``(v, ω)`` that moves the look-ahead point with velocity ``u`` (N, 2).

    v = cos θ·u_x + sin θ·u_y,  ω = (−sin θ·u_x + cos θ·u_y)/ℓ.
    """
    poses = np.asarray(poses, dtype=float)
    u = np.asarray(u, dtype=float)
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    v = c * u[:, 0] + s * u[:, 1]
    w = (-s * u[:, 0] + c * u[:, 1]) / ell
    return v, w


def unicycle_to_si(poses: ArrayLike, v: ArrayLike, w: ArrayLike, ell: float) -> FloatArray:
    """Velocity ``(N, 2)`` of the look-ahead point under unicycle command ``(v, ω)``: ṗ = M(θ)[v, ω]ᵀ."""
    poses = np.asarray(poses, dtype=float)
    v = np.asarray(v, dtype=float)
    w = np.asarray(w, dtype=float)
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    return np.column_stack((c * v - ell * s * w, s * v + ell * c * w))


# ---------------------------------------------------------------------------- the wheel map
def unicycle_to_wheels(v: ArrayLike, w: ArrayLike, params: UnicycleParams) -> tuple[FloatArray, FloatArray]:
    """Wheel speeds (ω_R, ω_L) in rad/s from (v, ω): ω_R,L = (2v ± ωL) / (2r)."""
    v = np.asarray(v, dtype=float)
    w = np.asarray(w, dtype=float)
    r, L = params.wheel_radius, params.axle_length
    return (2.0 * v + w * L) / (2.0 * r), (2.0 * v - w * L) / (2.0 * r)


def wheels_to_unicycle(right: ArrayLike, left: ArrayLike, params: UnicycleParams) -> tuple[FloatArray, FloatArray]:
    """(v, ω) from wheel speeds: v = r(ω_R + ω_L)/2, ω = r(ω_R − ω_L)/L."""
    right = np.asarray(right, dtype=float)
    left = np.asarray(left, dtype=float)
    r, L = params.wheel_radius, params.axle_length
    return r * (right + left) / 2.0, r * (right - left) / L


# ---------------------------------------------------------------------------- limits
def wheel_scale(v: ArrayLike, w: ArrayLike, params: UnicycleParams) -> FloatArray:
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


def limit_unicycle(v: ArrayLike, w: ArrayLike, params: UnicycleParams) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """Apply the wheel limits by one uniform scale per robot.

    Returns the limited ``(v, w)`` (new arrays) and a boolean ``(N,)`` mask of the
    robots whose command was scaled down (actuator saturation).
    """
    v = np.asarray(v, dtype=float)
    w = np.asarray(w, dtype=float)
    s = wheel_scale(v, w, params)
    return v * s, w * s, s < 1.0


def saturate(u: ArrayLike, limit: float | None) -> FloatArray:
    """Scale each robot's velocity ``(N, 2)`` m/s down to norm ≤ ``limit`` (direction kept).

    ``None`` or inf leaves finite rows unchanged. A row with NaN or inf becomes zero:
    a command nobody can read stops that robot. Returns a new array.
    """
    out = np.array(u, dtype=float)
    out[~np.all(np.isfinite(out), axis=1)] = 0.0
    if limit is None or not np.isfinite(limit):
        return out
    speed = np.hypot(out[:, 0], out[:, 1])
    fast = speed > limit  # only these are scaled (speed > 0 there): slower rows pass bit for bit
    scale = np.divide(limit, speed, out=np.ones_like(speed), where=fast)
    out = out * scale[:, None]
    # a subnormal limit leaves the scaled row a few units of the last place too long (subnormals
    # carry fewer bits): step such components towards zero until the row is within the limit
    for _ in range(8):  # a few ulps at most; bounded, over whole arrays
        over = fast & (np.hypot(out[:, 0], out[:, 1]) > limit)
        if not over.any():
            break
        out[over] = np.nextafter(out[over], 0.0)
    return out


# ---------------------------------------------------------------------------- the motion
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
    # f = sin(a)/a, g = (1 - cos a)/a with their Taylor series near 0 (when every robot takes one form, only that
    # form is computed: the same numbers np.where would pick).
    if not small.any():
        f = np.sin(a) / a
        g = (1.0 - np.cos(a)) / a
    elif small.all():
        f = 1.0 - a * a / 6.0
        g = a / 2.0 - a**3 / 24.0
    else:
        a_safe = np.where(small, 1.0, a)
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
