"""Cell integrals by fan-triangle quadrature (REFERENCE.md §5, notes/coverage.md §3.2).

For every cell V_i (fanned into triangles from its robot p_i) and a density snapshot::

    m_i = ∫ φ,   c_i = (1/m_i) ∫ q φ,   ∂c_i/∂t = (1/m_i) ∫ (q − c_i) φ_t,
    H_i = ∫ ‖q − p_i‖² φ,   I_i = ∫ ‖q − c_i‖² φ = H_i − m_i ‖p_i − c_i‖²,   H = Σ H_i.

All triangles of all cells are integrated at once with the 7-point degree-5 rule (Radon /
Dunavant) and reduced per cell with ``np.bincount``. A triangle near a bump of width σ_k (its
distance to μ_k below ``reach``·σ_k) is split 4-way ``L`` times, the smallest L with
diameter / 2^L ≤ ``resolution``·σ_k (capped at ``max_level``); triangles in the floor region are
not split. Moments are taken in coordinates relative to p_i, so they stay accurate for tiny cells.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from swarmdeck.coverage.density import GaussianMixture
from swarmdeck.coverage.voronoi import BoundedVoronoi

__all__ = ["CellMoments", "QuadratureOptions", "cell_moments", "triangle_rule"]


@dataclass(frozen=True)
class QuadratureOptions:
    """Accuracy knobs. resolution: sub-triangle diameter / σ of a nearby bump (≤). reach: a bump
    counts for a triangle within reach·σ of it. max_level: most 4-way splits of one fan triangle.
    min_level: splits applied to every triangle (for reference computations)."""

    resolution: float = 1.0
    reach: float = 7.0
    max_level: int = 5
    min_level: int = 0

    def __post_init__(self) -> None:
        if not (self.resolution > 0 and self.reach > 0):
            raise ValueError("resolution and reach must be > 0")
        if not (0 <= self.min_level <= self.max_level <= 8):
            raise ValueError("need 0 <= min_level <= max_level <= 8")


@dataclass(frozen=True)
class CellMoments:
    """Per-cell integrals. masses (N,) ∫φ; centroids (N, 2) [m]; dc_dt (N, 2) [m/s];
    dm_dt (N,) ∫φ_t; polar (N,) I_i = ∫‖q − c_i‖²φ; cost (N,) H_i = ∫‖q − p_i‖²φ;
    areas (N,) [m²]; massless (N,) bool: mass underflowed, centroid = area centroid;
    n_points: quadrature points used."""

    masses: NDArray[np.float64]
    centroids: NDArray[np.float64]
    dc_dt: NDArray[np.float64]
    dm_dt: NDArray[np.float64]
    polar: NDArray[np.float64]
    cost: NDArray[np.float64]
    areas: NDArray[np.float64]
    massless: NDArray[np.bool_]
    n_points: int

    @property
    def cost_H(self) -> float:
        """Locational cost H = Σ_i ∫_{V_i} ‖q − p_i‖² φ."""
        return float(self.cost.sum())


def _dunavant7() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """7-point degree-5 rule: barycentric points (7, 3) and weights (7,) summing to 1."""
    r = np.sqrt(15.0)
    b1, b2 = (6.0 + r) / 21.0, (6.0 - r) / 21.0
    a1, a2 = 1.0 - 2.0 * b1, 1.0 - 2.0 * b2
    w1, w2 = (155.0 + r) / 1200.0, (155.0 - r) / 1200.0
    pts = np.array([[1 / 3, 1 / 3, 1 / 3],
                    [a1, b1, b1], [b1, a1, b1], [b1, b1, a1],
                    [a2, b2, b2], [b2, a2, b2], [b2, b2, a2]])
    w = np.array([9.0 / 40.0, w1, w1, w1, w2, w2, w2])
    return pts, w


@lru_cache(maxsize=16)
def triangle_rule(level: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Composite 7-point rule on a triangle split 4-way ``level`` times.

    Returns barycentric points (7·4^L, 3) and weights (7·4^L,) summing to 1 (read-only).
    """
    tris = np.eye(3)[None]                          # (1, 3 vertices, 3 bary)
    for _ in range(level):
        a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
        ab, bc, ca = 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)
        tris = np.concatenate([np.stack([a, ab, ca], 1), np.stack([ab, b, bc], 1),
                               np.stack([ca, bc, c], 1), np.stack([bc, ca, ab], 1)])
    p7, w7 = _dunavant7()
    pts = np.einsum("pv,tvb->tpb", p7, tris).reshape(-1, 3)
    w = np.tile(w7, tris.shape[0]) / tris.shape[0]
    pts.setflags(write=False)
    w.setflags(write=False)
    return pts, w


def _levels(tri: NDArray[np.float64], density: GaussianMixture, opts: QuadratureOptions
            ) -> NDArray[np.intp]:
    """Subdivision level per triangle (T,) from the triangles (T, 3, 2) and the bumps."""
    t = tri.shape[0]
    level = np.full(t, opts.min_level, dtype=np.intp)
    live = (density.weight > 0.0) | (density.weight_dot != 0.0)
    if not np.any(live) or opts.max_level == opts.min_level:
        return level
    sig = np.sqrt(np.linalg.eigvalsh(density.cov[live])[:, 0])            # (K,)
    mu = density.mu[live]
    g = tri.mean(axis=1)                                                   # (T, 2)
    rad = np.sqrt(((tri - g[:, None]) ** 2).sum(axis=2)).max(axis=1)       # (T,)
    e = tri - np.roll(tri, 1, axis=1)
    diam = np.sqrt((e ** 2).sum(axis=2)).max(axis=1)                       # (T,)
    dist = np.sqrt(((g[:, None, :] - mu[None]) ** 2).sum(axis=2)) - rad[:, None]   # (T, K)
    near = dist < opts.reach * sig[None]
    ratio = np.where(near, diam[:, None] / (opts.resolution * sig[None]), 0.0).max(axis=1)
    with np.errstate(divide="ignore"):
        need = np.ceil(np.log2(np.maximum(ratio, 1e-300)))
    return np.clip(need, opts.min_level, opts.max_level).astype(np.intp)


def cell_moments(vor: BoundedVoronoi, density: GaussianMixture,
                 opts: QuadratureOptions = QuadratureOptions()) -> CellMoments:
    """Integrate φ and φ_t over every cell of ``vor``; see the module docstring."""
    n = vor.n
    p = vor.points
    cell = vor.tri_cell
    a = vor.vertices[vor.tri_a]
    b = vor.vertices[vor.tri_b]
    pc = p[cell]
    tri = np.stack([pc, a, b], axis=1)                                     # (T, 3, 2)
    ea, eb = a - pc, b - pc
    area = 0.5 * np.abs(ea[:, 0] * eb[:, 1] - ea[:, 1] * eb[:, 0])         # (T,)
    levels = _levels(tri, density, opts)
    acc = np.zeros((10, n))
    n_points = 0
    for lev in np.unique(levels):
        sel = np.flatnonzero(levels == lev)
        bary, w = triangle_rule(int(lev))
        # local coordinates relative to the robot: r = q − p_i
        r = bary[None, :, 1, None] * ea[sel, None, :] + bary[None, :, 2, None] * eb[sel, None, :]
        q = r + pc[sel, None, :]
        phi, phi_t = density.evaluate_both(q)                              # (S, P)
        wa = w[None, :] * area[sel, None]
        fw = phi * wa
        gw = phi_t * wa
        rx, ry = r[..., 0], r[..., 1]
        cs = cell[sel]
        for row, val in enumerate((fw, fw * rx, fw * ry, fw * (rx * rx + ry * ry),
                                   gw, gw * rx, gw * ry)):
            acc[row] += np.bincount(cs, weights=val.sum(axis=1), minlength=n)
        acc[7] += np.bincount(cs, weights=area[sel], minlength=n)
        acc[8] += np.bincount(cs, weights=(wa * rx).sum(axis=1), minlength=n)
        acc[9] += np.bincount(cs, weights=(wa * ry).sum(axis=1), minlength=n)
        n_points += phi.size
    m, mx, my, m2, g0, gx, gy, areas, ax, ay = acc
    if not (np.all(np.isfinite(acc))):
        raise ValueError("the density gave NaN or inf inside the arena")
    # A cell whose mass underflows (no floor, far from every bump) falls back to its area
    # centroid with ∂c/∂t = 0 and is flagged massless (its Jacobian rows are left out).
    massless = m <= 1e-12 * areas * max(density.peak, 1e-300)
    safe_m = np.where(massless, 1.0, m)
    off = np.column_stack([mx, my]) / safe_m[:, None]                      # c_i − p_i
    off[massless] = np.column_stack([ax, ay])[massless] / areas[massless, None]
    centroids = p + off
    dc_dt = (np.column_stack([gx, gy]) - off * g0[:, None]) / safe_m[:, None]
    dc_dt[massless] = 0.0
    polar = np.maximum(m2 - m * (off ** 2).sum(axis=1), 0.0)
    return CellMoments(masses=m, centroids=centroids, dc_dt=dc_dt, dm_dt=g0, polar=polar,
                       cost=m2, areas=areas, massless=massless, n_points=n_points)
