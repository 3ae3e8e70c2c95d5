"""The centroid Jacobian ∂c/∂p as a sparse block matrix from edge integrals (REFERENCE.md §5).

For a shared edge e_ij (d_ij = ‖p_j − p_i‖, ds arc length)::

    ∂c_i/∂p_j = (1/(m_i d_ij)) ∫_{e_ij} φ (q − c_i)(p_j − q)ᵀ ds          (neighbour block)
    ∂c_i/∂p_i = Σ_j (1/(m_i d_ij)) ∫_{e_ij} φ (q − c_i)(q − p_i)ᵀ ds     (self block)

walls add nothing. Row = component of c_i, column = component of p_j; the matrix is 2N × 2N
with rows/columns ordered (x_0, y_0, x_1, y_1, …), i.e. it acts on ``p.reshape(-1)``.
Each edge is split into pieces no longer than ``resolution``·σ of the nearby bumps and
integrated by Gauss–Legendre with ``nodes`` points per piece, all edges at once.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from swarmdeck.coverage.density import GaussianMixture
from swarmdeck.coverage.kernels import edge_blocks, edge_nodes
from swarmdeck.coverage.quadrature import CellMoments
from swarmdeck.coverage.voronoi import BoundedVoronoi

__all__ = ["EdgeOptions", "centroid_jacobian"]


@dataclass(frozen=True)
class EdgeOptions:
    """nodes: Gauss–Legendre points per edge piece; resolution: piece length / σ of a nearby
    bump (≤); reach: a bump counts for an edge within reach·σ of it; max_pieces per edge."""

    nodes: int = 6
    resolution: float = 1.0
    reach: float = 7.0
    max_pieces: int = 64

    def __post_init__(self) -> None:
        if not (1 <= self.nodes <= 64 and self.resolution > 0 and self.reach > 0
                and self.max_pieces >= 1):
            raise ValueError("need 1 <= nodes <= 64, resolution > 0, reach > 0, max_pieces >= 1")
        x, w = np.polynomial.legendre.leggauss(self.nodes)
        x, w = 0.5 * (x + 1.0), 0.5 * w            # on [0, 1], weights summing to 1
        x.setflags(write=False)
        w.setflags(write=False)
        object.__setattr__(self, "_gl", (x, w))

    def gauss_legendre(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Gauss–Legendre nodes on [0, 1] and weights summing to 1 (read-only)."""
        return self._gl  # type: ignore[attr-defined]


def _pieces(a: NDArray[np.float64], b: NDArray[np.float64], density: GaussianMixture,
            opts: EdgeOptions) -> NDArray[np.intp]:
    """Number of pieces per edge (E,) from its end points (E, 2) and the live bumps."""
    e = a.shape[0]
    live = (density.weight > 0.0) | (density.weight_dot != 0.0)
    if not np.any(live) or e == 0:
        return np.ones(e, dtype=np.intp)
    sig = density.std_min[live]
    mu = density.mu[live]
    mid = 0.5 * (a + b)
    length = np.hypot(*(b - a).T)
    dist = np.sqrt(((mid[:, None, :] - mu[None]) ** 2).sum(axis=2)) - 0.5 * length[:, None]
    near = dist < opts.reach * sig[None]
    ratio = np.where(near, length[:, None] / (opts.resolution * sig[None]), 0.0).max(axis=1)
    return np.clip(np.ceil(ratio), 1, opts.max_pieces).astype(np.intp)


def centroid_jacobian(vor: BoundedVoronoi, moments: CellMoments, density: GaussianMixture,
                      opts: EdgeOptions = EdgeOptions()) -> sp.csr_array:
    """∂c/∂p (2N × 2N, CSR) for the diagram ``vor`` with its cell ``moments`` under ``density``.

    Cells flagged massless in ``moments`` get zero rows.
    """
    n = vor.n
    pairs = vor.edge_pairs
    if pairs.shape[0] == 0:
        return sp.csr_array((2 * n, 2 * n))
    seg = vor.vertices[vor.edge_vertices]                                  # (E, 2, 2)
    a, b = seg[:, 0], seg[:, 1]
    pieces = _pieces(a, b, density, opts)
    x, w = opts.gauss_legendre()
    # Node positions along every edge: piece k of n_e, node x_l → s = (k + x_l) / n_e (coverage/kernels.py).
    length = np.hypot(*(b - a).T)
    mid = 0.5 * (a + b)
    r, wq, edge_q, nodes = edge_nodes(a, b, mid, length, pieces, x, w)       # r = q − mid (Q, 2)
    phi = density.evaluate(nodes)
    fw = phi * wq
    i, j = pairs[:, 0], pairs[:, 1]
    p, c, m = vor.points, moments.centroids, moments.masses
    d = np.hypot(*(p[j] - p[i]).T)
    inv_i = np.where(moments.massless[i], 0.0, 1.0 / (np.where(moments.massless[i], 1.0, m[i]) * d))
    inv_j = np.where(moments.massless[j], 0.0, 1.0 / (np.where(moments.massless[j], 1.0, m[j]) * d))
    # Edge moments about the midpoint (S0 = ∫φ, S1 = ∫φ r, S2 = ∫φ r rᵀ) and the (4E, 2, 2) blocks
    # ∂c_i/∂p_j, −…∂c_i/∂p_i, ∂c_j/∂p_i, −…∂c_j/∂p_j: compiled (coverage/kernels.py).
    blocks = edge_blocks(fw, r, edge_q, mid, c[i], c[j], p[i], p[j], inv_i, inv_j)
    brow = np.concatenate([i, i, j, j])
    bcol = np.concatenate([j, i, i, j])
    rows = (2 * brow[:, None, None] + np.arange(2)[None, :, None]) + np.zeros((1, 1, 2), dtype=np.intp)
    cols = (2 * bcol[:, None, None] + np.arange(2)[None, None, :]) + np.zeros((1, 2, 1), dtype=np.intp)
    mat = sp.coo_array((blocks.ravel(), (rows.ravel(), cols.ravel())), shape=(2 * n, 2 * n))
    return mat.tocsr()
