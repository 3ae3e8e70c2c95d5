"""Compiled ray-cast kernels (numba through :mod:`swarmdeck.core.compiled`): the same arithmetic as the numpy
paths of :mod:`swarmdeck.sensing.geometry`, one loop per candidate instead of one array per operation.

:data:`AVAILABLE` False (no numba) leaves the callers on their numpy paths.
"""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.compiled import AVAILABLE, jit

__all__ = ["AVAILABLE", "pair_circle_hits", "segment_hits"]


@jit
def pair_circle_hits(a: NDArray[np.intp], b: NDArray[np.intp], origins: NDArray[np.float64],
                     directions: NDArray[np.float64], centres: NDArray[np.float64], radius: float, k: int,
                     best: NDArray[np.float64]) -> None:
    """For each directed robot pair (a[p], b[p]): the K rays of robot a (rows a·K … a·K+K−1 of ``origins`` and
    ``directions`` ``(N·K, 2)``) against the circle of ``radius`` around ``centres[b]``; lowers ``best`` ``(N·K,)``
    in place to each ray's first hit (an origin inside the circle: 0)."""
    r2 = radius * radius
    for p in range(a.shape[0]):
        cx = centres[b[p], 0]
        cy = centres[b[p], 1]
        base = a[p] * k
        for s in range(k):
            r = base + s
            wx = cx - origins[r, 0]
            wy = cy - origins[r, 1]
            bb = wx * directions[r, 0] + wy * directions[r, 1]
            cc = (wx * wx + wy * wy) - r2
            if cc <= 0.0:
                t = 0.0
            else:
                disc = bb * bb - cc
                if bb < 0.0 or disc < 0.0:
                    continue
                t = bb - math.sqrt(disc)
            if t < best[r]:
                best[r] = t


@jit
def segment_hits(origins: NDArray[np.float64], directions: NDArray[np.float64], segments: NDArray[np.float64],
                 parallel: float, best: NDArray[np.float64]) -> None:
    """Lowers ``best`` ``(R,)`` to each ray's first crossing of a segment of ``segments`` ``(M, 2, 2)`` (ends
    included; |cross| ≤ ``parallel``: parallel, no crossing)."""
    for r in range(origins.shape[0]):
        ox = origins[r, 0]
        oy = origins[r, 1]
        ux = directions[r, 0]
        uy = directions[r, 1]
        for m in range(segments.shape[0]):
            px = segments[m, 0, 0]
            py = segments[m, 0, 1]
            dx = segments[m, 1, 0] - px
            dy = segments[m, 1, 1] - py
            denom = ux * dy - uy * dx
            if abs(denom) <= parallel:
                continue
            wx = px - ox
            wy = py - oy
            t = (wx * dy - wy * dx) / denom
            s = (wx * uy - wy * ux) / denom
            if t >= 0.0 and s >= 0.0 and s <= 1.0 and t < best[r]:
                best[r] = t
