"""The smoothstep S(u) = 3u² − 2u³: fades with a finite rate (REFERENCE.md §5).

Used wherever a density term fades in or out (touch contacts, painted bumps, pulses),
so φ_t stays finite: S(0) = 0, S(1) = 1, S'(0) = S'(1) = 0.
"""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray


def smoothstep(u: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """S(u) on u clipped to [0, 1] and dS/du = 6u(1 − u) (0 outside (0, 1)); any shape, elementwise."""
    uc = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
    return uc * uc * (3.0 - 2.0 * uc), 6.0 * uc * (1.0 - uc)


def inverse_smoothstep(f: float) -> float:
    """u in [0, 1] with S(u) = f (f clipped to [0, 1])."""
    f = min(max(f, 0.0), 1.0)
    return 0.5 - math.sin(math.asin(1.0 - 2.0 * f) / 3.0)
