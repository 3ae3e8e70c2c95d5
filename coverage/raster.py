"""Raster oracle for the cell integrals: label a fine grid by nearest robot and sum.

Independent of the Voronoi construction and of the triangle quadrature, so tests can check
both against it. Its centroid error is O(h) absolute (pixels cut by cell boundaries) and it
gives no edges, so it is a test oracle, not a controller component (notes/coverage.md §3.2).
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial import cKDTree

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.coverage.density import GaussianMixture
from swarmdeck.coverage.quadrature import CellMoments

__all__ = ["raster_moments"]


def raster_moments(points: ArrayLike, density: GaussianMixture,
                   bounds: Bounds = DEFAULT_BOUNDS,
                   h: float = 0.005) -> CellMoments:
    """Midpoint-rule moments on a grid of spacing ≈ h [m] labelled by the nearest robot."""
    p = np.asarray(points, dtype=float)
    n = p.shape[0]
    b = Bounds.of(bounds)
    x0, x1, y0, y1 = b
    nx, ny = int(np.ceil(b.width / h)), int(np.ceil(b.height / h))
    hx, hy = b.width / nx, b.height / ny
    gx = x0 + hx * (np.arange(nx) + 0.5)
    gy = y0 + hy * (np.arange(ny) + 0.5)
    q = np.stack(np.meshgrid(gx, gy), axis=-1).reshape(-1, 2)
    _, lab = cKDTree(p).query(q)
    phi, phi_t = density.evaluate_both(q)
    da = hx * hy
    r = q - p[lab]

    def s(v: np.ndarray) -> np.ndarray:
        return np.bincount(lab, weights=v * da, minlength=n)

    m = s(phi)
    off = np.column_stack([s(phi * r[:, 0]), s(phi * r[:, 1])]) / m[:, None]
    g0 = s(phi_t)
    dc = (np.column_stack([s(phi_t * r[:, 0]), s(phi_t * r[:, 1])]) - off * g0[:, None]) / m[:, None]
    cost = s(phi * (r ** 2).sum(axis=1))
    return CellMoments(masses=m, centroids=p + off, dc_dt=dc, dm_dt=g0,
                       polar=cost - m * (off ** 2).sum(axis=1), cost=cost,
                       areas=np.bincount(lab, minlength=n) * da,  # type: ignore[arg-type]
                       massless=np.zeros(n, dtype=bool), n_points=q.shape[0])
