"""The bounded Voronoi diagram's post-processing, compiled (REFERENCE.md §5; issue 27 item 2).

After qhull's Delaunay triangulation, :mod:`swarmdeck.coverage.voronoi` reads the diagram off it
in three vectorised numpy passes: the ridges (circumcentres, dual edges, which ones leave the
rectangle), the assembly (clip, drop zero-length ridges, fan triangles, shared edges sorted) and the
area check. At N = 5000 those passes were ≈ 60 % of the Voronoi stage and held the GIL the whole time;
here each is one numba kernel (``nogil``, :mod:`swarmdeck.core.compiled`) doing the same floating-point
operations in the same order as its numpy reference in :mod:`swarmdeck.coverage.voronoi` (``…_numpy``):
elementwise products and quotients, the 2-vector sums left to right, the per-cell sums in input order
like ``np.bincount``, a stable sort for ``np.lexsort``; so the diagram is bit-for-bit the numpy one
(tests/coverage/test_coverage_voronoi_compiled.py). Used when :data:`swarmdeck.coverage.kernels.AVAILABLE`
(the one switch for the compiled coverage paths).

Index arrays: ``simplices`` and ``neighbors`` are qhull's (int32); robots/ridges are returned with the
dtypes the numpy path gives (robot indices in the simplices' dtype, vertex indices intp).
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.compiled import jit

__all__ = ["areas_compiled", "assemble_compiled", "polygon_order", "ridges_compiled"]


@jit
def _div(num: float, den: float) -> float:  # pragma: no cover - compiled
    """num / den with IEEE semantics at den == ±0 (numba's default error model would raise)."""
    if den != 0.0:
        return num / den
    if num != num or num == 0.0:
        return math.nan
    return math.copysign(math.inf, num) * math.copysign(1.0, den)


@jit
def _ridges(simp: Any, nb: Any, allp: Any, n: int, cb0: float, cb1: float, cb2: float, cb3: float,
            tol: float) -> Any:  # pragma: no cover - compiled
    t_count = simp.shape[0]
    cc = np.empty((t_count, 2))
    for t in range(t_count):
        ax = allp[simp[t, 0], 0]
        ay = allp[simp[t, 0], 1]
        bx = allp[simp[t, 1], 0] - ax
        by = allp[simp[t, 1], 1] - ay
        cx = allp[simp[t, 2], 0] - ax
        cy = allp[simp[t, 2], 1] - ay
        d = 2.0 * (bx * cy - by * cx)
        b2 = bx * bx + by * by
        c2 = cx * cx + cy * cy
        cc[t, 0] = ax + _div(cy * b2 - by * c2, d)
        cc[t, 1] = ay + _div(bx * c2 - cx * b2, d)
    count = 0
    for t in range(t_count):
        for k in range(3):
            tn = nb[t, k]
            if tn < 0 or t < tn:
                if simp[t, (k + 1) % 3] < n or simp[t, (k + 2) % 3] < n:
                    count += 1
    pairs = np.empty((count, 2), dtype=np.int64)
    seg = np.empty((count, 2, 2))
    out = np.zeros((4, count), dtype=np.bool_)
    r = 0
    for t in range(t_count):
        for k in range(3):
            tn = nb[t, k]
            if not (tn < 0 or t < tn):
                continue
            pa = simp[t, (k + 1) % 3]
            pb = simp[t, (k + 2) % 3]
            if not (pa < n or pb < n):
                continue
            pairs[r, 0] = pa
            pairs[r, 1] = pb
            seg[r, 0, 0] = cc[t, 0]
            seg[r, 0, 1] = cc[t, 1]
            if tn >= 0:
                seg[r, 1, 0] = cc[tn, 0]
                seg[r, 1, 1] = cc[tn, 1]
            else:
                seg[r, 1, 0] = math.nan
                seg[r, 1, 1] = math.nan
            finite = True
            for j in range(2):
                for c in range(2):
                    if not math.isfinite(seg[r, j, c]):
                        finite = False
            for j in range(2):
                vx = seg[r, j, 0]
                vy = seg[r, j, 1]
                if vx < cb0 - tol or not finite:
                    out[0, r] = True
                if vx > cb1 + tol or not finite:
                    out[1, r] = True
                if vy < cb2 - tol or not finite:
                    out[2, r] = True
                if vy > cb3 + tol or not finite:
                    out[3, r] = True
            r += 1
    return pairs, seg, out


def ridges_compiled(simplices: NDArray[np.intp], neighbors: NDArray[np.intp], allp: NDArray[np.float64],
                    n: int, cb: tuple[float, float, float, float],
                    tol: float) -> tuple[NDArray[np.intp], NDArray[np.float64], NDArray[np.bool_]]:
    """The real ridges of a Delaunay triangulation of ``allp`` (M, 2) m (robots first, ``n`` of them):
    robot pairs (R, 2) (the simplices' dtype), Voronoi vertex pairs (R, 2, 2) m (NaN for a hull ridge's
    infinite end) and, per wall (x0, x1, y0, y1), which ridges leave the rectangle ``cb`` by more than
    ``tol`` m or are infinite (4, R). :func:`swarmdeck.coverage.voronoi._ridges_numpy` bit for bit."""
    pairs, seg, out = _ridges(np.ascontiguousarray(simplices), np.ascontiguousarray(neighbors),
                              np.ascontiguousarray(allp, dtype=np.float64), int(n), float(cb[0]), float(cb[1]),
                              float(cb[2]), float(cb[3]), float(tol))
    return pairs.astype(simplices.dtype, copy=False), seg, out


@jit
def _assemble(pairs: Any, seg: Any, points: Any, centre0: float, centre1: float, x0: float, x1: float, y0: float,
              y1: float, min_len: float, n: int) -> Any:  # pragma: no cover - compiled
    r_count = pairs.shape[0]
    verts = np.empty((2 * r_count, 2))
    for r in range(r_count):
        for j in range(2):
            vx = seg[r, j, 0] + centre0
            vy = seg[r, j, 1] + centre1
            verts[2 * r + j, 0] = min(max(vx, x0), x1) if vx == vx else vx
            verts[2 * r + j, 1] = min(max(vy, y0), y1) if vy == vy else vy
    keep = np.zeros(r_count, dtype=np.bool_)
    n_keep = 0
    n_cells = 0
    n_inner = 0
    for r in range(r_count):
        dx = verts[2 * r + 1, 0] - verts[2 * r, 0]
        dy = verts[2 * r + 1, 1] - verts[2 * r, 1]
        if np.hypot(dx, dy) > min_len:
            keep[r] = True
            n_keep += 1
            a_real = pairs[r, 0] < n
            b_real = pairs[r, 1] < n
            n_cells += a_real + b_real
            if a_real and b_real:
                n_inner += 1
    cells = np.empty(n_cells, dtype=np.int64)
    va = np.empty(n_cells, dtype=np.int64)
    vb = np.empty(n_cells, dtype=np.int64)
    m = 0
    for side in range(2):
        for r in range(r_count):
            if keep[r] and pairs[r, side] < n:
                cells[m] = pairs[r, side]
                va[m] = 2 * r
                vb[m] = 2 * r + 1
                m += 1
    for m in range(n_cells):
        c = cells[m]
        qax = verts[va[m], 0] - points[c, 0]
        qay = verts[va[m], 1] - points[c, 1]
        qbx = verts[vb[m], 0] - points[c, 0]
        qby = verts[vb[m], 1] - points[c, 1]
        if qax * qby - qay * qbx < 0.0:
            a = va[m]
            va[m] = vb[m]
            vb[m] = a
    epairs = np.empty((n_inner, 2), dtype=np.int64)
    evs = np.empty((n_inner, 2), dtype=np.int64)
    key = np.empty(n_inner, dtype=np.int64)
    m = 0
    for r in range(r_count):
        if keep[r] and pairs[r, 0] < n and pairs[r, 1] < n:
            lo = min(pairs[r, 0], pairs[r, 1])
            hi = max(pairs[r, 0], pairs[r, 1])
            epairs[m, 0] = lo
            epairs[m, 1] = hi
            evs[m, 0] = 2 * r
            evs[m, 1] = 2 * r + 1
            key[m] = lo * n + hi
            m += 1
    order = np.argsort(key, kind="mergesort")
    return verts, cells, va, vb, epairs[order], evs[order]


def assemble_compiled(pairs: NDArray[np.intp], seg: NDArray[np.float64], points: NDArray[np.float64],
                      centre: NDArray[np.float64], bounds: tuple[float, float, float, float],
                      n: int) -> tuple[NDArray[np.float64], NDArray[np.intp], NDArray[np.intp], NDArray[np.intp],
                                       NDArray[np.intp], NDArray[np.intp]]:
    """The diagram from the settled real ridges (``pairs`` (R, 2), centred vertex pairs ``seg`` (R, 2, 2) m):
    vertices (2R, 2) m (un-centred, clipped to ``bounds``), fan triangles (cell, vertex a, vertex b) counter-
    clockwise, and the shared edges (robot pairs i < j sorted, their vertex pairs), zero-length ridges dropped.
    :func:`swarmdeck.coverage.voronoi._assemble_numpy` bit for bit (same dtypes)."""
    x0, x1, y0, y1 = (float(v) for v in bounds)
    min_len = 1e-12 * max(x1 - x0, y1 - y0)
    verts, cells, va, vb, epairs, evs = _assemble(
        np.ascontiguousarray(pairs), np.ascontiguousarray(seg, dtype=np.float64),
        np.ascontiguousarray(points, dtype=np.float64), float(centre[0]), float(centre[1]),
        x0, x1, y0, y1, float(min_len), int(n))
    return (verts, cells.astype(pairs.dtype, copy=False), va, vb, epairs.astype(pairs.dtype, copy=False), evs)


@jit
def _areas(points: Any, vertices: Any, tri_cell: Any, tri_a: Any, tri_b: Any, n: int) -> Any:  # pragma: no cover - compiled
    acc = np.zeros(n)
    for t in range(tri_cell.shape[0]):
        c = tri_cell[t]
        px = points[c, 0]
        py = points[c, 1]
        ax = vertices[tri_a[t], 0] - px
        ay = vertices[tri_a[t], 1] - py
        bx = vertices[tri_b[t], 0] - px
        by = vertices[tri_b[t], 1] - py
        acc[c] += 0.5 * (ax * by - ay * bx)
    return acc


def areas_compiled(points: NDArray[np.float64], vertices: NDArray[np.float64], tri_cell: NDArray[np.intp],
                   tri_a: NDArray[np.intp], tri_b: NDArray[np.intp], n: int) -> NDArray[np.float64]:
    """Cell areas (n,) m² from the fan triangles: :meth:`swarmdeck.coverage.voronoi.BoundedVoronoi.areas` bit for
    bit (each triangle added to its cell in input order, as ``np.bincount``)."""
    return _areas(np.ascontiguousarray(points, dtype=np.float64), np.ascontiguousarray(vertices, dtype=np.float64),
                  np.ascontiguousarray(tri_cell), np.ascontiguousarray(tri_a), np.ascontiguousarray(tri_b), int(n))


@jit
def _polygon_order(tri_cell: Any, ang: Any, n: int) -> Any:  # pragma: no cover - compiled
    count = np.zeros(n + 1, dtype=np.int64)
    for t in range(tri_cell.shape[0]):
        count[tri_cell[t] + 1] += 1
    for c in range(n):
        count[c + 1] += count[c]
    offsets = count.copy()
    order = np.empty(tri_cell.shape[0], dtype=np.int64)
    fill = count[:n].copy()
    for t in range(tri_cell.shape[0]):                # stable counting sort by cell
        c = tri_cell[t]
        order[fill[c]] = t
        fill[c] += 1
    for c in range(n):                                # stable insertion sort by angle within a cell
        lo, hi = offsets[c], offsets[c + 1]
        for s in range(lo + 1, hi):
            cur = order[s]
            key = ang[cur]
            j = s
            while j > lo and ang[order[j - 1]] > key:
                order[j] = order[j - 1]
                j -= 1
            order[j] = cur
    return order, offsets


def polygon_order(tri_cell: NDArray[np.intp], ang: NDArray[np.float64],
                  n: int) -> tuple[NDArray[np.intp], NDArray[np.int64]]:
    """``np.lexsort((ang, tri_cell))`` (triangles by cell, then by angle, ties in input order) and the cells'
    offsets (n + 1,) into it (``cumsum`` of the per-cell counts): what
    :meth:`~swarmdeck.coverage.voronoi.BoundedVoronoi.cell_polygons` sorts, bit for bit."""
    return _polygon_order(np.ascontiguousarray(tri_cell), np.ascontiguousarray(ang, dtype=np.float64), int(n))
