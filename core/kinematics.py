"""The look-ahead (near-identity) diffeomorphism between unicycle and single integrator.

Olfati-Saber's construction (REFERENCE.md §1): the point
``p = (x + ℓ cos θ, y + ℓ sin θ)`` of a unicycle moves as
``ṗ = M(θ) [v, ω]ᵀ`` with ``M = [[cos θ, −ℓ sin θ], [sin θ, ℓ cos θ]]``, which is
invertible for ℓ > 0. So a single-integrator velocity for ``p`` maps exactly
to one unicycle command. Shapes: poses ``(N, 3)``, velocities ``(N, 2)``.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def lookahead_points(poses: ArrayLike, ell: float) -> FloatArray:
    """Look-ahead points ``(N, 2)`` of poses ``(N, 3)``, m."""
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
