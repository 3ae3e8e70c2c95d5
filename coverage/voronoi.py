"""Bounded Voronoi cells on the arena rectangle by the mirror trick (REFERENCE.md §5).

Robots are reflected in the walls and the Voronoi diagram of robots plus reflections is read off
a ``scipy.spatial.Delaunay`` triangulation (vertices = circumcentres, ridges = dual edges; this
is several times faster than ``scipy.spatial.Voronoi``, which builds Python lists). The cell of a
real robot in that diagram is exactly its Voronoi cell clipped to the rectangle (the bisector of
a robot and its own reflection is the wall; a reflection is never closer than its original to a
point of the rectangle), ridges between two real robots are the shared edges e_ij, ridges
between a robot and a reflection are wall edges. Only robots near a wall are reflected at
first; robots whose cell is unbounded or leaves the rectangle get reflected too and the diagram
is rebuilt (at worst all 4N reflections, the textbook mirror trick). Every cell is convex and
contains its robot, so it is fanned into triangles (robot, ridge vertex a, ridge vertex b)
straight from the ridge list, with no per-robot loop.

The mirror trick breaks on exact duplicates and on robots exactly on a wall, so
:func:`precondition_positions` first clamps robots ``wall_margin`` inside and pushes apart robots
closer than ``min_separation`` (a documented repair; the count is reported).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import Delaunay, QhullError, cKDTree

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds, check_bounds
from swarmdeck.coverage import kernels, voronoi_kernels
from swarmdeck.coverage.cells import CellPolygons

__all__ = ["BoundedVoronoi", "bounded_voronoi", "precondition_positions"]

_GOLDEN_ANGLE = np.pi * (3.0 - np.sqrt(5.0))


def precondition_positions(
    positions: ArrayLike,
    bounds: Bounds = DEFAULT_BOUNDS,
    wall_margin: float = 1e-6,
    min_separation: float = 1e-3,
) -> tuple[NDArray[np.float64], int]:
    """Make positions safe for the mirror-trick Voronoi.

    positions (N, 2) [m] → (repaired (N, 2) new array, number of robots moved). Robots are
    clamped ``wall_margin`` inside the rectangle; pairs closer than ``min_separation`` are pushed
    apart symmetrically along their difference (exact duplicates along a deterministic direction
    that depends on the robot index), repeating a few times. Raises ValueError for a wrong shape
    or non-finite values.
    """
    p = np.array(positions, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 1:
        raise ValueError(f"positions must have shape (N, 2) with N >= 1, got {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ValueError("positions contain NaN or inf")
    x0, x1, y0, y1 = check_bounds(bounds)
    lo = np.array([x0 + wall_margin, y0 + wall_margin])
    hi = np.array([x1 - wall_margin, y1 - wall_margin])
    orig = p.copy()
    np.clip(p, lo, hi, out=p)
    n = p.shape[0]
    if n > 1 and min_separation > 0.0:
        for _ in range(20):
            pairs = cKDTree(p).query_pairs(min_separation, output_type="ndarray")
            if pairs.size == 0:
                break
            i, j = pairs[:, 0], pairs[:, 1]
            d = p[j] - p[i]
            gap = np.hypot(d[:, 0], d[:, 1])
            tiny = gap < 1e-12
            ang = _GOLDEN_ANGLE * (i + 1.0)
            d[tiny] = np.column_stack([np.cos(ang[tiny]), np.sin(ang[tiny])])
            u = d / np.where(tiny, 1.0, gap)[:, None]
            push = 0.5 * (1.05 * min_separation - np.where(tiny, 0.0, gap))
            shift = u * push[:, None]
            np.add.at(p, i, -shift)
            np.add.at(p, j, shift)
            np.clip(p, lo, hi, out=p)
    moved = int(np.count_nonzero(np.any(p != orig, axis=1)))
    return p, moved


@dataclass(frozen=True)
class BoundedVoronoi:
    """The bounded Voronoi diagram of N robots on a rectangle.

    points (N, 2): generators [m]. vertices (V, 2): Voronoi vertices [m].
    tri_cell (T,), tri_a (T,), tri_b (T,): fan triangles (robot, vertex a, vertex b), oriented
    counter-clockwise; every triangle lies in the cell of robot ``tri_cell``.
    edge_pairs (E, 2) int: robots (i < j) sharing a Voronoi edge of positive length;
    edge_vertices (E, 2) int: its two vertex indices. bounds: the rectangle.
    """

    points: NDArray[np.float64]
    vertices: NDArray[np.float64]
    tri_cell: NDArray[np.intp]
    tri_a: NDArray[np.intp]
    tri_b: NDArray[np.intp]
    edge_pairs: NDArray[np.intp]
    edge_vertices: NDArray[np.intp]
    bounds: tuple[float, float, float, float]

    @property
    def n(self) -> int:
        return int(self.points.shape[0])

    def edge_segments(self) -> NDArray[np.float64]:
        """Shared edges as segments (E, 2, 2) [m] (for drawing)."""
        return self.vertices[self.edge_vertices]

    def areas(self) -> NDArray[np.float64]:
        """Cell areas (N,) [m²] from the fan triangles."""
        if kernels.AVAILABLE:
            return voronoi_kernels.areas_compiled(self.points, self.vertices, self.tri_cell, self.tri_a, self.tri_b,
                                                  self.n)
        p = self.points[self.tri_cell]
        a = self.vertices[self.tri_a] - p
        b = self.vertices[self.tri_b] - p
        tri = 0.5 * (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
        return np.bincount(self.tri_cell, weights=tri, minlength=self.n)  # type: ignore[return-value]  # bincount with weights is float64

    def cell_polygons(self) -> CellPolygons:
        """Cells as counter-clockwise polygons, flat: N polygons (V_i, 2) [m] as one
        :class:`~swarmdeck.coverage.cells.CellPolygons` (read-only)."""
        p = self.points[self.tri_cell]
        a = self.vertices[self.tri_a] - p
        ang = np.arctan2(a[:, 1], a[:, 0])
        if kernels.AVAILABLE:
            order, offsets = voronoi_kernels.polygon_order(self.tri_cell, ang, self.n)
            return CellPolygons(self.vertices[self.tri_a[order]], offsets)
        order = np.lexsort((ang, self.tri_cell))
        verts = self.vertices[self.tri_a[order]]
        offsets = np.zeros(self.n + 1, dtype=np.int64)
        np.cumsum(np.bincount(self.tri_cell, minlength=self.n), out=offsets[1:])
        return CellPolygons(verts, offsets)

    def polygons(self) -> list[NDArray[np.float64]]:
        """Cells as counter-clockwise polygons, a list of N read-only arrays (V_i, 2) [m]
        (:meth:`cell_polygons` without the list)."""
        return list(self.cell_polygons())

    def neighbours_of(self, i: int) -> NDArray[np.intp]:
        """Robots sharing an edge with robot i."""
        e = self.edge_pairs
        return np.sort(np.concatenate([e[e[:, 0] == i, 1], e[e[:, 1] == i, 0]]))


def _circumcentres(pts: NDArray[np.float64], simplices: NDArray[np.intp]) -> NDArray[np.float64]:
    a = pts[simplices[:, 0]]
    b = pts[simplices[:, 1]] - a
    c = pts[simplices[:, 2]] - a
    d = 2.0 * (b[:, 0] * c[:, 1] - b[:, 1] * c[:, 0])
    b2 = (b * b).sum(axis=1)
    c2 = (c * c).sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        ux = (c[:, 1] * b2 - b[:, 1] * c2) / d
        uy = (b[:, 0] * c2 - c[:, 0] * b2) / d
    return a + np.column_stack([ux, uy])


def _mirrors(points: NDArray[np.float64], bounds: tuple[float, float, float, float],
             masks: NDArray[np.bool_]) -> NDArray[np.float64]:
    """Real points followed by the reflections selected by masks (4, N) (walls x0, x1, y0, y1)."""
    x0, x1, y0, y1 = bounds
    x, y = points[:, 0], points[:, 1]
    parts = [points]
    for w, m in enumerate(masks):
        if w == 0:
            parts.append(np.column_stack([2.0 * x0 - x[m], y[m]]))
        elif w == 1:
            parts.append(np.column_stack([2.0 * x1 - x[m], y[m]]))
        elif w == 2:
            parts.append(np.column_stack([x[m], 2.0 * y0 - y[m]]))
        else:
            parts.append(np.column_stack([x[m], 2.0 * y1 - y[m]]))
    return np.concatenate(parts)


def _ridges_delaunay(allp: NDArray[np.float64]) -> tuple[NDArray[np.intp], NDArray[np.float64],
                                                         NDArray[np.float64]]:
    """Voronoi ridges from a Delaunay triangulation: point pairs (R, 2), vertex coords (R, 2, 2).

    Also returns the circumcentres. Hull edges give ridges with a NaN vertex (infinite).
    """
    tri = Delaunay(allp)
    return _ridges_of(tri.simplices, tri.neighbors, allp)


def _ridges_of(simp: NDArray[np.intp], nb: NDArray[np.intp],
               allp: NDArray[np.float64]) -> tuple[NDArray[np.intp], NDArray[np.float64], NDArray[np.float64]]:
    cc = _circumcentres(allp, simp)
    t = np.repeat(np.arange(simp.shape[0]), 3)
    k = np.tile(np.arange(3), simp.shape[0])
    tn = nb.ravel()
    keep = (tn < 0) | (t < tn)
    t, k, tn = t[keep], k[keep], tn[keep]
    pa = simp[t, (k + 1) % 3]
    pb = simp[t, (k + 2) % 3]
    va = cc[t]
    vb = np.where((tn >= 0)[:, None], cc[np.maximum(tn, 0)], np.nan)
    return np.column_stack([pa, pb]), np.stack([va, vb], axis=1), cc


def _ridges_numpy(simp: NDArray[np.intp], nb: NDArray[np.intp], allp: NDArray[np.float64], n: int,
                  cb: tuple[float, float, float, float],
                  tol: float) -> tuple[NDArray[np.intp], NDArray[np.float64], NDArray[np.bool_]]:
    """The real ridges (a robot on at least one side) of the triangulation ``simp``/``nb`` of ``allp``: robot
    pairs (R, 2), vertex pairs (R, 2, 2) m, and per wall which ridges leave ``cb`` by > ``tol`` or are
    infinite (4, R). The reference of :func:`~swarmdeck.coverage.voronoi_kernels.ridges_compiled`."""
    pairs, seg, _cc = _ridges_of(simp, nb, allp)
    real = (pairs < n).any(axis=1)
    pairs, seg = pairs[real], seg[real]
    bad_inf = ~np.all(np.isfinite(seg), axis=(1, 2))
    v = seg.reshape(-1, 2)
    out = np.stack([v[:, 0] < cb[0] - tol, v[:, 0] > cb[1] + tol,
                    v[:, 1] < cb[2] - tol, v[:, 1] > cb[3] + tol])          # (4, 2R)
    out = out.reshape(4, -1, 2).any(axis=2) | bad_inf[None, :]             # (4, R)
    return pairs, seg, out


def _assemble_numpy(pairs: NDArray[np.intp], seg: NDArray[np.float64], points: NDArray[np.float64],
                    centre: NDArray[np.float64], bounds: tuple[float, float, float, float],
                    n: int) -> tuple[NDArray[np.float64], NDArray[np.intp], NDArray[np.intp], NDArray[np.intp],
                                     NDArray[np.intp], NDArray[np.intp]]:
    """The diagram's arrays from the settled real ridges: vertices, fan triangles (cell, a, b), shared edges
    (pairs, vertex pairs) sorted. The reference of :func:`~swarmdeck.coverage.voronoi_kernels.assemble_compiled`."""
    x0, x1, y0, y1 = bounds
    verts = seg.reshape(-1, 2) + centre
    np.clip(verts, [x0, y0], [x1, y1], out=verts)
    rv = np.arange(verts.shape[0]).reshape(-1, 2)
    d = verts[rv[:, 1]] - verts[rv[:, 0]]
    long_enough = np.hypot(d[:, 0], d[:, 1]) > 1e-12 * max(x1 - x0, y1 - y0)
    rp, rv = pairs[long_enough], rv[long_enough]
    # Fan triangles: one per (real robot, ridge) incidence.
    cells = np.concatenate([rp[:, 0], rp[:, 1]])
    va = np.concatenate([rv[:, 0], rv[:, 0]])
    vb = np.concatenate([rv[:, 1], rv[:, 1]])
    real = cells < n
    cells, va, vb = cells[real], va[real], vb[real]
    qa = verts[va] - points[cells]
    qb = verts[vb] - points[cells]
    flip = qa[:, 0] * qb[:, 1] - qa[:, 1] * qb[:, 0] < 0.0
    va, vb = np.where(flip, vb, va), np.where(flip, va, vb)
    inner = (rp < n).all(axis=1)
    epairs = np.sort(rp[inner], axis=1)
    evs = rv[inner]
    order = np.lexsort((epairs[:, 1], epairs[:, 0]))
    return verts, cells, va, vb, epairs[order], evs[order]


def _diagram(points: NDArray[np.float64], bounds: tuple[float, float, float, float],
             full: bool) -> BoundedVoronoi:
    """Bounded diagram from a Delaunay triangulation of the robots and of the reflections needed.

    Starts with the reflections of robots near each wall (all of them if ``full``), then adds the
    reflections of every robot whose cell is unbounded or leaves the rectangle, until every real
    cell lies in the rectangle; such a cell then equals the clipped cell (a reflection is never
    closer than its original to a point of the rectangle).
    """
    b = Bounds.of(bounds)
    x0, x1, y0, y1 = b
    n = points.shape[0]
    centre = np.array(b.centre)
    pts = points - centre
    cb = (x0 - centre[0], x1 - centre[0], y0 - centre[1], y1 - centre[1])
    wall_dist = np.stack([pts[:, 0] - cb[0], cb[1] - pts[:, 0], pts[:, 1] - cb[2], cb[3] - pts[:, 1]])
    if full or n <= 16:
        masks = np.ones((4, n), dtype=bool)
    else:
        spacing = np.sqrt(b.area / n)
        masks = wall_dist < 2.5 * spacing
    tol = 1e-9 * max(b.width, b.height)
    compiled = kernels.AVAILABLE
    for _ in range(8):
        allp = _mirrors(pts, cb, masks)
        tri = Delaunay(allp)
        pairs, seg, out = (voronoi_kernels.ridges_compiled if compiled else _ridges_numpy)(
            tri.simplices, tri.neighbors, allp, n, cb, tol)
        if not out.any():
            break
        add = np.zeros((4, n), dtype=bool)
        for w in range(4):
            owners = pairs[out[w]].ravel()
            add[w, owners[owners < n]] = True
        if not np.any(add & ~masks):
            masks[:] = True
            if full:
                raise QhullError("cells leave the rectangle even with all reflections")
            full = True
        masks |= add
    else:
        raise QhullError("bounded Voronoi did not settle")
    verts, cells, va, vb, epairs, evs = (voronoi_kernels.assemble_compiled if compiled else _assemble_numpy)(
        pairs, seg, points, centre, (x0, x1, y0, y1), n)
    return BoundedVoronoi(points=points, vertices=verts, tri_cell=cells, tri_a=va, tri_b=vb,
                          edge_pairs=epairs, edge_vertices=evs, bounds=bounds)


def bounded_voronoi(points: ArrayLike,
                    bounds: Bounds = DEFAULT_BOUNDS) -> BoundedVoronoi:
    """Bounded Voronoi diagram of ``points`` (N, 2) [m] strictly inside ``bounds``.

    Call :func:`precondition_positions` first for raw robot positions. The result is checked:
    the cell areas must sum to the rectangle's area (relative 1e-9); otherwise it is rebuilt with
    every reflection, and a RuntimeError is raised if that fails too.
    """
    b = check_bounds(bounds)
    p = np.array(points, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2 or p.shape[0] < 1 or not np.all(np.isfinite(p)):
        raise ValueError(f"points must be a finite (N, 2) array with N >= 1, got shape {p.shape}")
    if np.any(p[:, 0] <= b[0]) or np.any(p[:, 0] >= b[1]) or np.any(p[:, 1] <= b[2]) \
            or np.any(p[:, 1] >= b[3]):
        raise ValueError("points must lie strictly inside bounds (use precondition_positions)")
    total = b.area
    for full in (False, True):
        try:
            vor = _diagram(p, b, full)
        except QhullError:
            continue
        areas = vor.areas()
        if abs(areas.sum() - total) <= 1e-9 * total and np.all(areas > 0.0):
            return vor
    raise RuntimeError("bounded Voronoi failed: cell areas do not sum to the arena "
                       "(duplicate robots? use precondition_positions)")
