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

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.checks import in_range
from swarmdeck.coverage.density import GaussianMixture
from swarmdeck.coverage.kernels import cell_sums, quadrature_points, refine_need
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
        if not (in_range(self.resolution, 0.0, lo_open=True) and in_range(self.reach, 0.0, lo_open=True)):
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


def triangle_rule(level: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Composite 7-point rule on a triangle split 4-way ``level`` times.

    Returns barycentric points (7·4^L, 3) and weights (7·4^L,) summing to 1.
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
    return pts, w


def _split(tri: NDArray[np.float64], cell: NDArray[np.intp]
           ) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """4-way midpoint split of triangles (T, 3, 2) → (4T, 3, 2), keeping orientation."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    ab, bc, ca = 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)
    out = np.concatenate([np.stack([a, ab, ca], 1), np.stack([ab, b, bc], 1),
                          np.stack([ca, bc, c], 1), np.stack([bc, ca, ab], 1)])
    return out, np.tile(cell, 4)


def _bisect(tri: NDArray[np.float64], cell: NDArray[np.intp], len2: NDArray[np.float64]
            ) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """Split every triangle (T, 3, 2) in two at the midpoint of its longest edge, keeping the
    orientation. len2 (T, 3): squared lengths of the edges opposite vertices 0, 1, 2."""
    k = np.argmax(len2, axis=1)
    perm = np.array([[0, 1, 2], [1, 2, 0], [2, 0, 1]])[k]           # longest edge opposite vertex 0
    t = tri[np.arange(tri.shape[0])[:, None], perm]
    a, b, c = t[:, 0], t[:, 1], t[:, 2]
    m = 0.5 * (b + c)
    out = np.concatenate([np.stack([a, b, m], 1), np.stack([a, m, c], 1)])
    return out, np.tile(cell, 2)


def _refine(tri: NDArray[np.float64], cell: NDArray[np.intp], origin: NDArray[np.float64],
            density: GaussianMixture, opts: QuadratureOptions
            ) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """Adaptive subdivision. tri (T, 3, 2) in coordinates relative to ``origin[cell]``.

    Every triangle is split 4-way ``min_level`` times; then, round by round, the triangles that
    are within ``reach``·σ_k of a bump k and whose longest edge exceeds ``resolution``·σ_k are
    bisected at their longest edge, up to 2·(max_level − min_level) rounds (each round halves
    the area; longest-edge bisection also repairs the slivers of the fan). Returns the final
    triangles and their cells.
    """
    for _ in range(opts.min_level):
        tri, cell = _split(tri, cell)
    live = (density.weight > 0.0) | (density.weight_dot != 0.0)
    if not np.any(live) or opts.max_level == opts.min_level:
        return tri, cell
    sig = density.std_min[live]            # (K,)
    mu = density.mu[live]
    reach = opts.reach * sig
    done_t, done_c = [], []
    for _ in range(2 * (opts.max_level - opts.min_level)):
        need, len2 = refine_need(tri, cell, origin, mu, reach, opts.resolution * sig)   # coverage/kernels.py
        if not need.any():
            break
        done_t.append(tri[~need])
        done_c.append(cell[~need])
        tri, cell = _bisect(tri[need], cell[need], len2[need])
    done_t.append(tri)
    done_c.append(cell)
    return np.concatenate(done_t), np.concatenate(done_c)


def cell_moments(vor: BoundedVoronoi, density: GaussianMixture,
                 opts: QuadratureOptions = QuadratureOptions()) -> CellMoments:
    """Integrate φ and φ_t over every cell of ``vor``; see the module docstring."""
    n = vor.n
    p = vor.points
    pc = p[vor.tri_cell]
    tri = np.stack([np.zeros_like(pc), vor.vertices[vor.tri_a] - pc, vor.vertices[vor.tri_b] - pc],
                   axis=1)                                                 # (T, 3, 2) local
    geo_area = 0.5 * np.abs(tri[:, 1, 0] * tri[:, 2, 1] - tri[:, 1, 1] * tri[:, 2, 0])
    areas = np.bincount(vor.tri_cell, weights=geo_area, minlength=n)
    tri, cell = _refine(tri, vor.tri_cell, p, density, opts)
    order = np.argsort(cell, kind="stable")          # cells are compact: keeps points local
    tri, cell = tri[order], cell[order]
    bary, w = _dunavant7()
    area, r, q = quadrature_points(tri, cell, bary, p)      # (T,), (T, 7, 2) = q − p_i, (T, 7, 2); compiled
    phi, phi_t = density.evaluate_both(q)                                   # (T, 7)
    acc = cell_sums(phi, phi_t, r, area, w, cell, n)                     # compiled (coverage/kernels.py)
    n_points = phi.size
    m, mx, my, m2, g0, gx, gy, ax, ay = acc
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
                       cost=m2, areas=areas, massless=massless, n_points=n_points)  # type: ignore[arg-type]
