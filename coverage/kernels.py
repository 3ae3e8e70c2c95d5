"""The coverage sums, compiled: cell-moment and edge-moment accumulation (REFERENCE.md §5).

The two reductions that dominated a coverage tick after the Voronoi diagram — the nine per-cell sums
of :func:`~swarmdeck.coverage.quadrature.cell_moments` and the per-edge moments and 2×2 blocks of
:func:`~swarmdeck.coverage.jacobian.centroid_jacobian` — as numba kernels (through
:mod:`swarmdeck.core.compiled`, cached on disk). Each kernel does the same floating-point
operations in the same order as the numpy expression it replaces (products element by element,
the 7 quadrature points of a triangle summed left to right, triangles/nodes added to their cell/edge
in input order as ``np.bincount`` does), so the results are bit-for-bit today's
(tests/coverage/test_coverage_compiled.py). Without numba (``AVAILABLE`` False) the callers keep
their numpy paths, :func:`cell_sums_numpy` and :func:`edge_blocks_numpy`, the reference the tests
compare against.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.compiled import AVAILABLE, jit

__all__ = ["AVAILABLE", "cell_sums", "cell_sums_numpy", "edge_blocks", "edge_blocks_numpy", "edge_nodes",
           "edge_nodes_numpy", "quadrature_points", "quadrature_points_numpy", "refine_need", "refine_need_numpy"]


def cell_sums_numpy(phi: NDArray[np.float64], phi_t: NDArray[np.float64], r: NDArray[np.float64],
                    area: NDArray[np.float64], w: NDArray[np.float64], cell: NDArray[np.intp],
                    n: int) -> NDArray[np.float64]:
    """The nine per-cell sums (9, n): ∫φ, ∫φ r_x, ∫φ r_y, ∫φ‖r‖², ∫φ_t, ∫φ_t r_x, ∫φ_t r_y, ∫r_x, ∫r_y.

    phi, phi_t (T, P) density and its rate at the P quadrature points of T triangles; r (T, P, 2) m,
    the points relative to their robot; area (T,) m²; w (P,) rule weights; cell (T,) the owning cell.
    """
    wa = w[None, :] * area[:, None]
    fw = phi * wa
    gw = phi_t * wa
    rx, ry = r[..., 0], r[..., 1]
    acc = np.empty((9, n))
    for row, val in enumerate((fw, fw * rx, fw * ry, fw * (rx * rx + ry * ry),
                               gw, gw * rx, gw * ry, wa * rx, wa * ry)):
        acc[row] = np.bincount(cell, weights=val.sum(axis=1), minlength=n)
    return acc


@jit
def _cell_sums_compiled(phi, phi_t, r, area, w, cell, n):  # pragma: no cover - compiled
    acc = np.zeros((9, n))
    t_count, p_count = phi.shape
    for t in range(t_count):
        s = np.zeros(9)
        for q in range(p_count):
            wa = w[q] * area[t]
            fw = phi[t, q] * wa
            gw = phi_t[t, q] * wa
            rx = r[t, q, 0]
            ry = r[t, q, 1]
            s[0] += fw
            s[1] += fw * rx
            s[2] += fw * ry
            s[3] += fw * (rx * rx + ry * ry)
            s[4] += gw
            s[5] += gw * rx
            s[6] += gw * ry
            s[7] += wa * rx
            s[8] += wa * ry
        c = cell[t]
        for k in range(9):
            acc[k, c] += s[k]
    return acc


def cell_sums(phi: NDArray[np.float64], phi_t: NDArray[np.float64], r: NDArray[np.float64],
              area: NDArray[np.float64], w: NDArray[np.float64], cell: NDArray[np.intp],
              n: int) -> NDArray[np.float64]:
    """:func:`cell_sums_numpy`, compiled when numba is available (the same bits)."""
    if not AVAILABLE:
        return cell_sums_numpy(phi, phi_t, r, area, w, cell, n)
    return _cell_sums_compiled(np.ascontiguousarray(phi), np.ascontiguousarray(phi_t), np.ascontiguousarray(r),
                               np.ascontiguousarray(area), np.ascontiguousarray(w),
                               np.ascontiguousarray(cell, dtype=np.intp), int(n))


def _edge_moments_numpy(fw: NDArray[np.float64], r: NDArray[np.float64], edge_q: NDArray[np.intp], ne: int
                        ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    S0: NDArray[np.float64] = np.bincount(edge_q, weights=fw, minlength=ne)  # type: ignore[assignment]  # bincount with weights is float64
    S1: NDArray[np.float64] = np.column_stack([np.bincount(edge_q, weights=fw * r[:, c], minlength=ne) for c in (0, 1)])
    S2: NDArray[np.float64] = np.empty((ne, 2, 2))
    S2[:, 0, 0] = np.bincount(edge_q, weights=fw * r[:, 0] * r[:, 0], minlength=ne)
    S2[:, 1, 1] = np.bincount(edge_q, weights=fw * r[:, 1] * r[:, 1], minlength=ne)
    S2[:, 0, 1] = S2[:, 1, 0] = np.bincount(edge_q, weights=fw * r[:, 0] * r[:, 1], minlength=ne)
    return S0, S1, S2


def edge_blocks_numpy(fw: NDArray[np.float64], r: NDArray[np.float64], edge_q: NDArray[np.intp],
                      mid: NDArray[np.float64], ci: NDArray[np.float64], cj: NDArray[np.float64],
                      pi: NDArray[np.float64], pj: NDArray[np.float64], inv_i: NDArray[np.float64],
                      inv_j: NDArray[np.float64]) -> NDArray[np.float64]:
    """The Jacobian's 2×2 blocks (4E, 2, 2) from the edge quadrature: ∂c_i/∂p_j, the edge's part of
    ∂c_i/∂p_i, ∂c_j/∂p_i, the edge's part of ∂c_j/∂p_j (in that order, E each).

    fw (Q,) φ·ds weights at the Q nodes; r (Q, 2) m, the nodes relative to their edge's midpoint;
    edge_q (Q,) each node's edge; mid (E, 2) m midpoints; ci, cj (E, 2) m centroids and pi, pj (E, 2) m
    robots of the edge's two cells; inv_i, inv_j (E,) 1/(m d) (0 for a massless cell).
    """
    S0, S1, S2 = _edge_moments_numpy(fw, r, edge_q, mid.shape[0])

    def f(av: NDArray[np.float64], vv: NDArray[np.float64]) -> NDArray[np.float64]:
        """∫ φ (q − a)(v − q)ᵀ ds per edge (E, 2, 2) for points a, v (E, 2)."""
        a_ = av - mid
        v_ = vv - mid
        return (S1[:, :, None] * v_[:, None, :] - S2 - S0[:, None, None] * a_[:, :, None] * v_[:, None, :]
                + a_[:, :, None] * S1[:, None, :])

    return np.concatenate([
        inv_i[:, None, None] * f(ci, pj),          # ∂c_i/∂p_j
        -inv_i[:, None, None] * f(ci, pi),         # contribution to ∂c_i/∂p_i
        inv_j[:, None, None] * f(cj, pi),          # ∂c_j/∂p_i
        -inv_j[:, None, None] * f(cj, pj),         # contribution to ∂c_j/∂p_j
    ])


@jit
def _edge_blocks_compiled(fw, r, edge_q, mid, ci, cj, pi, pj, inv_i, inv_j):  # pragma: no cover - compiled
    ne = mid.shape[0]
    S0 = np.zeros(ne)
    S1 = np.zeros((ne, 2))
    S2 = np.zeros((ne, 3))                         # xx, yy, xy
    for q in range(fw.shape[0]):
        e = edge_q[q]
        f0 = fw[q]
        rx = r[q, 0]
        ry = r[q, 1]
        S0[e] += f0
        S1[e, 0] += f0 * rx
        S1[e, 1] += f0 * ry
        S2[e, 0] += f0 * rx * rx
        S2[e, 1] += f0 * ry * ry
        S2[e, 2] += f0 * rx * ry
    out = np.empty((4 * ne, 2, 2))
    for e in range(ne):
        s2 = np.empty((2, 2))
        s2[0, 0] = S2[e, 0]
        s2[1, 1] = S2[e, 1]
        s2[0, 1] = S2[e, 2]
        s2[1, 0] = S2[e, 2]
        for blk in range(4):
            if blk == 0:
                a0, a1, v0, v1, scale = ci[e, 0], ci[e, 1], pj[e, 0], pj[e, 1], inv_i[e]
            elif blk == 1:
                a0, a1, v0, v1, scale = ci[e, 0], ci[e, 1], pi[e, 0], pi[e, 1], -inv_i[e]
            elif blk == 2:
                a0, a1, v0, v1, scale = cj[e, 0], cj[e, 1], pi[e, 0], pi[e, 1], inv_j[e]
            else:
                a0, a1, v0, v1, scale = cj[e, 0], cj[e, 1], pj[e, 0], pj[e, 1], -inv_j[e]
            a_ = (a0 - mid[e, 0], a1 - mid[e, 1])
            v_ = (v0 - mid[e, 0], v1 - mid[e, 1])
            for u in range(2):
                for v in range(2):
                    val = (S1[e, u] * v_[v] - s2[u, v] - S0[e] * a_[u] * v_[v] + a_[u] * S1[e, v])
                    out[blk * ne + e, u, v] = scale * val
    return out


def edge_blocks(fw: NDArray[np.float64], r: NDArray[np.float64], edge_q: NDArray[np.intp],
                mid: NDArray[np.float64], ci: NDArray[np.float64], cj: NDArray[np.float64],
                pi: NDArray[np.float64], pj: NDArray[np.float64], inv_i: NDArray[np.float64],
                inv_j: NDArray[np.float64]) -> NDArray[np.float64]:
    """:func:`edge_blocks_numpy`, compiled when numba is available (the same bits)."""
    if not AVAILABLE:
        return edge_blocks_numpy(fw, r, edge_q, mid, ci, cj, pi, pj, inv_i, inv_j)
    c = np.ascontiguousarray
    return _edge_blocks_compiled(c(fw), c(r), c(edge_q, dtype=np.intp), c(mid), c(ci), c(cj), c(pi), c(pj),
                                 c(inv_i), c(inv_j))


def refine_need_numpy(tri: NDArray[np.float64], cell: NDArray[np.intp], origin: NDArray[np.float64],
                      mu: NDArray[np.float64], reach: NDArray[np.float64], res_sig: NDArray[np.float64]
                      ) -> tuple[NDArray[np.bool_], NDArray[np.float64]]:
    """Which triangles one round of the adaptive quadrature splits, and their squared edge lengths.

    tri (T, 3, 2) m relative to ``origin[cell]``; mu (K, 2) m live bumps; reach (K,) m; res_sig (K,) m the
    longest edge allowed near each bump. Returns need (T,) (within reach of a bump whose limit the
    longest edge exceeds) and len2 (T, 3) m², the edge opposite each vertex.
    """
    g = tri.mean(axis=1)                                               # local centroid
    rad = np.sqrt(((tri - g[:, None]) ** 2).sum(axis=2)).max(axis=1)
    e = tri[:, [2, 0, 1]] - tri[:, [1, 2, 0]]                          # edge opposite vertex i
    len2 = (e ** 2).sum(axis=2)
    diam = np.sqrt(len2.max(axis=1))
    gw = g + origin[cell]
    dist = np.sqrt(((gw[:, None, :] - mu[None]) ** 2).sum(axis=2)) - rad[:, None]   # (T, K)
    need = ((dist < reach[None]) & (diam[:, None] > res_sig[None])).any(axis=1)
    return need, len2


@jit
def _refine_need_compiled(tri, cell, origin, mu, reach, res_sig):  # pragma: no cover - compiled
    t_count = tri.shape[0]
    need = np.zeros(t_count, np.bool_)
    len2 = np.empty((t_count, 3))
    for t in range(t_count):
        gx = (tri[t, 0, 0] + tri[t, 1, 0] + tri[t, 2, 0]) / 3.0
        gy = (tri[t, 0, 1] + tri[t, 1, 1] + tri[t, 2, 1]) / 3.0
        rad = 0.0
        for v in range(3):
            dx = tri[t, v, 0] - gx
            dy = tri[t, v, 1] - gy
            r = np.sqrt(dx * dx + dy * dy)
            if v == 0 or r > rad:
                rad = r
        big = 0.0
        for v in range(3):
            a = (v + 2) % 3
            b = (v + 1) % 3
            ex = tri[t, a, 0] - tri[t, b, 0]
            ey = tri[t, a, 1] - tri[t, b, 1]
            l2 = ex * ex + ey * ey
            len2[t, v] = l2
            if v == 0 or l2 > big:
                big = l2
        diam = np.sqrt(big)
        wx = gx + origin[cell[t], 0]
        wy = gy + origin[cell[t], 1]
        for k in range(mu.shape[0]):
            dx = wx - mu[k, 0]
            dy = wy - mu[k, 1]
            if np.sqrt(dx * dx + dy * dy) - rad < reach[k] and diam > res_sig[k]:
                need[t] = True
                break
    return need, len2


def refine_need(tri: NDArray[np.float64], cell: NDArray[np.intp], origin: NDArray[np.float64],
                mu: NDArray[np.float64], reach: NDArray[np.float64], res_sig: NDArray[np.float64]
                ) -> tuple[NDArray[np.bool_], NDArray[np.float64]]:
    """:func:`refine_need_numpy`, compiled when numba is available (the same bits)."""
    if not AVAILABLE:
        return refine_need_numpy(tri, cell, origin, mu, reach, res_sig)
    c = np.ascontiguousarray
    return _refine_need_compiled(c(tri), c(cell, dtype=np.intp), c(origin), c(mu), c(reach), c(res_sig))


def edge_nodes_numpy(a: NDArray[np.float64], b: NDArray[np.float64], mid: NDArray[np.float64],
                     length: NDArray[np.float64], pieces: NDArray[np.intp], x: NDArray[np.float64],
                     w: NDArray[np.float64]
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.intp], NDArray[np.float64]]:
    """The Jacobian's edge quadrature nodes: edge e from a[e] to b[e] (m) cut into pieces[e] pieces, the
    Gauss–Legendre nodes x (on [0, 1], weights w summing to 1) on each. Returns r (Q, 2) m the nodes
    relative to their edge's midpoint ``mid``, wq (Q,) m the ds weights, edge_q (Q,) each node's edge, and
    q (Q, 2) m the nodes themselves (r + mid)."""
    edge = np.repeat(np.arange(a.shape[0]), pieces)
    first = np.repeat(np.cumsum(pieces) - pieces, pieces)
    k = np.arange(edge.size) - first
    npc = pieces[edge]
    s = ((k[:, None] + x[None, :]) / npc[:, None]).ravel()                 # (Q,)
    edge_q = np.repeat(edge, x.size)
    wq = (np.tile(w, edge.size) / np.repeat(npc, x.size)) * length[edge_q]  # ds weights
    r = (a[edge_q] - mid[edge_q]) + s[:, None] * (b - a)[edge_q]            # q − mid (Q, 2)
    return r, wq, edge_q, r + mid[edge_q]


@jit
def _edge_nodes_compiled(a, b, mid, length, pieces, x, w):  # pragma: no cover - compiled
    nx = x.shape[0]
    total = 0
    for e in range(a.shape[0]):
        total += pieces[e]
    nq = total * nx
    r = np.empty((nq, 2))
    q = np.empty((nq, 2))
    wq = np.empty(nq)
    edge_q = np.empty(nq, np.intp)
    i = 0
    for e in range(a.shape[0]):
        npc = pieces[e]
        fn = float(npc)
        dx = b[e, 0] - a[e, 0]
        dy = b[e, 1] - a[e, 1]
        ox = a[e, 0] - mid[e, 0]
        oy = a[e, 1] - mid[e, 1]
        for kk in range(npc):
            for li in range(nx):
                s = (float(kk) + x[li]) / fn
                rx = ox + s * dx
                ry = oy + s * dy
                r[i, 0] = rx
                r[i, 1] = ry
                q[i, 0] = rx + mid[e, 0]
                q[i, 1] = ry + mid[e, 1]
                wq[i] = (w[li] / fn) * length[e]
                edge_q[i] = e
                i += 1
    return r, wq, edge_q, q


def edge_nodes(a: NDArray[np.float64], b: NDArray[np.float64], mid: NDArray[np.float64],
               length: NDArray[np.float64], pieces: NDArray[np.intp], x: NDArray[np.float64],
               w: NDArray[np.float64]
               ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.intp], NDArray[np.float64]]:
    """:func:`edge_nodes_numpy`, compiled when numba is available (the same bits)."""
    if not AVAILABLE:
        return edge_nodes_numpy(a, b, mid, length, pieces, x, w)
    c = np.ascontiguousarray
    return _edge_nodes_compiled(c(a), c(b), c(mid), c(length), c(pieces, dtype=np.intp), c(x), c(w))


def quadrature_points_numpy(tri: NDArray[np.float64], cell: NDArray[np.intp], bary: NDArray[np.float64],
                            origin: NDArray[np.float64]
                            ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The quadrature points of T triangles: tri (T, 3, 2) m relative to their robot ``origin[cell]``
    ((N, 2) m), bary (P, 3) barycentric rule points → areas (T,) m², the points relative to the robot r
    (T, P, 2) m and absolute q (T, P, 2) m (the code that was inline in ``cell_moments``)."""
    ea, eb = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    area = 0.5 * np.abs(ea[:, 0] * eb[:, 1] - ea[:, 1] * eb[:, 0])
    r = (bary[None, :, 0, None] * tri[:, None, 0] + bary[None, :, 1, None] * tri[:, None, 1]
         + bary[None, :, 2, None] * tri[:, None, 2])
    return area, r, r + origin[cell][:, None, :]


@jit
def _quadrature_points_compiled(tri, cell, bary, origin):  # pragma: no cover - compiled
    t_count, p_count = tri.shape[0], bary.shape[0]
    area = np.empty(t_count)
    r = np.empty((t_count, p_count, 2))
    q = np.empty((t_count, p_count, 2))
    for t in range(t_count):
        eax = tri[t, 1, 0] - tri[t, 0, 0]
        eay = tri[t, 1, 1] - tri[t, 0, 1]
        ebx = tri[t, 2, 0] - tri[t, 0, 0]
        eby = tri[t, 2, 1] - tri[t, 0, 1]
        area[t] = 0.5 * abs(eax * eby - eay * ebx)
        c = cell[t]
        for j in range(p_count):
            for d in range(2):
                v = bary[j, 0] * tri[t, 0, d] + bary[j, 1] * tri[t, 1, d] + bary[j, 2] * tri[t, 2, d]
                r[t, j, d] = v
                q[t, j, d] = v + origin[c, d]
    return area, r, q


def quadrature_points(tri: NDArray[np.float64], cell: NDArray[np.intp], bary: NDArray[np.float64],
                      origin: NDArray[np.float64]
                      ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """:func:`quadrature_points_numpy`, compiled when numba is available (the same bits)."""
    if not AVAILABLE:
        return quadrature_points_numpy(tri, cell, bary, origin)
    return _quadrature_points_compiled(np.ascontiguousarray(tri, dtype=np.float64),
                                       np.ascontiguousarray(cell, dtype=np.intp),
                                       np.ascontiguousarray(bary, dtype=np.float64),
                                       np.ascontiguousarray(origin, dtype=np.float64))
