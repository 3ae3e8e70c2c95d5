"""The GRITSBot's motion for the simulator: the exact unicycle step and heading wrap.

The robot's constants, the look-ahead map, the wheel map and the wheel limits are
in :mod:`swarmdeck.core.kinematics` (shared with safety). All functions are pure
and vectorised over robots: ``v`` and ``w`` are ``(N,)`` arrays, poses ``(N, 3)``
rows ``[x, y, θ]`` in metres and radians.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


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
