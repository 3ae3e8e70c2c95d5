"""Predict how tightly a CVT packs robots at the density peak (REFERENCE.md §5, notes §2.4).

A centroidal Voronoi tessellation with many generators has point density ∝ √φ in 2-D, so
λ(q) ≈ N √φ(q) / ∫_Q √φ robots per m² and the (hexagonal) spacing is ≈ 1.07 / √λ(q). When the
predicted spacing at the peak is below the barrier's safety distance D_s, the safety filter will
be active all the time: the operator is warned.
"""
from __future__ import annotations

import numpy as np

from swarmdeck.coverage.density import GaussianMixture

__all__ = ["predicted_spacing", "packing_warning"]


def predicted_spacing(density: GaussianMixture, n_robots: int,
                      bounds: tuple[float, float, float, float],
                      grid: int = 64) -> tuple[float, tuple[float, float]]:
    """(spacing [m] at the densest point, that point (x, y) [m]) for ``n_robots`` robots.

    ∫√φ is a midpoint sum on a ``grid`` × (proportional) grid; the peak is the larger of the grid
    maximum and φ at the bump centres inside the arena.
    """
    if n_robots < 1:
        raise ValueError(f"n_robots must be >= 1, got {n_robots}")
    x0, x1, y0, y1 = bounds
    nx = int(grid)
    ny = max(4, int(round(grid * (y1 - y0) / (x1 - x0))))
    hx, hy = (x1 - x0) / nx, (y1 - y0) / ny
    gx = x0 + hx * (np.arange(nx) + 0.5)
    gy = y0 + hy * (np.arange(ny) + 0.5)
    q = np.stack(np.meshgrid(gx, gy), axis=-1).reshape(-1, 2)
    inside = density.mu[(density.mu[:, 0] >= x0) & (density.mu[:, 0] <= x1)
                        & (density.mu[:, 1] >= y0) & (density.mu[:, 1] <= y1)]
    pts = np.concatenate([q, inside])
    root = np.sqrt(np.maximum(density.evaluate(pts), 0.0))
    total = root[: q.shape[0]].sum() * hx * hy
    k = int(np.argmax(root))
    lam = n_robots * root[k] / total
    return float(1.07 / np.sqrt(lam)), (float(pts[k, 0]), float(pts[k, 1]))


def packing_warning(density: GaussianMixture, n_robots: int,
                    bounds: tuple[float, float, float, float],
                    safety_distance: float) -> str | None:
    """A one-line warning when the predicted peak spacing is below ``safety_distance`` [m]."""
    if n_robots < 2:
        return None
    spacing, (x, y) = predicted_spacing(density, n_robots, bounds)
    if spacing >= safety_distance:
        return None
    return (f"density packs {n_robots} robots ≈{spacing:.3f} m apart near ({x:.2f}, {y:.2f}), "
            f"below the safety distance {safety_distance:.3f} m: the barrier will hold them "
            f"apart all the time (widen the bumps, raise the floor or use fewer robots)")
