"""Line-segment obstacles on the arena floor: one frozen type, its validation and its geometry.

An obstacle set is ``M`` line segments, an ``(M, 2, 2)`` float array in the arena frame, metres:
``segments[k] = [[x0, y0], [x1, y1]]`` — the Robotarium 2.x ``obstacles`` argument has the same
shape (REFERENCE.md §15). A polygon is the closed chain of its edges (:func:`polygon_segments`).

Everything is vectorised over robots and segments; the spatial query :func:`segments_near` cuts
segments into pieces no longer than a cell and asks one k-d tree of the points, so a robot far from
every segment costs nothing and no ``N × M`` array is formed beyond the candidate pairs.

Bad input is refused with :class:`ObstacleError` (a ValueError) naming the segment by its index:
a wrong shape, NaN/inf, a zero-length segment, a segment outside the arena, a segment within
reach of a start pose or a charger slot (:meth:`Obstacles.check_clear`).
"""
from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .bounds import Bounds
from .constants import LOOKAHEAD, SAFETY_DISTANCE
from .errors import SwarmdeckError
from .graphs import DENSE_PAIRS_ROBOTS

__all__ = ["ObstacleError", "Obstacles", "polygon_segments", "point_segment_distance",
           "nearest_points", "segments_near", "segments_cross", "MIN_SEGMENT_LENGTH", "START_CLEARANCE"]

#: m: a segment shorter than this has no direction (a point, not a segment) and is refused.
MIN_SEGMENT_LENGTH = 1e-6
#: m: how far a start pose or a charger slot (a robot's centre) must be from every segment: the barrier's
#: margin D_s/2 plus the look-ahead ℓ, so the look-ahead point starts in the safe set whatever the heading.
START_CLEARANCE: float = SAFETY_DISTANCE / 2 + LOOKAHEAD
_PIECE = 0.25  # m: segments are cut into pieces of at most this length for the k-d tree query


class ObstacleError(ValueError, SwarmdeckError):
    """An obstacle set that cannot be used; the message names the segment (by index) and what is wrong."""


def _as_segments(value: ArrayLike, name: str) -> NDArray[np.float64]:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ObstacleError(f"{name} must be numbers of shape (M, 2, 2) [[x0, y0], [x1, y1]] in m: {exc}") from None
    if arr.size == 0:
        return np.zeros((0, 2, 2))
    if arr.ndim != 3 or arr.shape[1:] != (2, 2):
        raise ObstacleError(f"{name} must have shape (M, 2, 2) [[x0, y0], [x1, y1]] in m, got {arr.shape}")
    bad = np.flatnonzero(~np.all(np.isfinite(arr), axis=(1, 2)))
    if bad.size:
        raise ObstacleError(f"{name}: segment {int(bad[0])} has NaN or inf coordinates {arr[bad[0]].tolist()}"
                            + (f" (and {bad.size - 1} more)" if bad.size > 1 else ""))
    length = np.linalg.norm(arr[:, 1] - arr[:, 0], axis=1)
    short = np.flatnonzero(length < MIN_SEGMENT_LENGTH)
    if short.size:
        raise ObstacleError(f"{name}: segment {int(short[0])} has zero length (both ends at "
                            f"{arr[short[0], 0].tolist()})")
    return arr


@dataclass(frozen=True, eq=False)
class Obstacles:
    """M line segments, ``segments`` ``(M, 2, 2)`` float m (a read-only copy), checked on construction.

    Equality and hash are by value (the segments' bytes), so configurations holding one compare as
    values. ``Obstacles.none()`` is the empty set (M = 0).
    """

    segments: NDArray[np.float64]

    def __post_init__(self) -> None:
        arr = _as_segments(self.segments, "obstacles")
        arr.setflags(write=False)
        object.__setattr__(self, "segments", arr)

    # ---------------------------------------------------------------- construction
    @classmethod
    def none(cls) -> Obstacles:
        """No obstacles (M = 0)."""
        return cls(np.zeros((0, 2, 2)))

    @classmethod
    def of(cls, value: Obstacles | ArrayLike | None) -> Obstacles:
        """``value`` as Obstacles: an Obstacles, None (none), an (M, 2, 2) array, or a list of segments and
        polygons as in the config (:meth:`from_config`)."""
        if value is None:
            return cls.none()
        if isinstance(value, Obstacles):
            return value
        if isinstance(value, dict) or (isinstance(value, Sequence) and value and isinstance(value[0], dict)):
            return cls.from_config(value)
        return cls(value)  # type: ignore[arg-type]

    @classmethod
    def from_polygons(cls, polygons: Iterable[ArrayLike], segments: ArrayLike | None = None) -> Obstacles:
        """Closed polygons (each ``(K, 2)`` vertices, m, K ≥ 3) and optional loose segments ``(M, 2, 2)``."""
        parts = [polygon_segments(p, closed=True, name=f"polygon {i}") for i, p in enumerate(polygons)]
        if segments is not None:
            parts.insert(0, _as_segments(segments, "segments"))
        return cls(np.concatenate(parts) if parts else np.zeros((0, 2, 2)))

    @classmethod
    def from_config(cls, value: object) -> Obstacles:
        """From a config value: a list of entries, each ``[[x0, y0], [x1, y1]]`` (a segment), a table
        ``{segment = [[x0, y0], [x1, y1]]}``, ``{polygon = [[x, y], ...]}`` (closed) or
        ``{polyline = [[x, y], ...]}`` (open). ObstacleError naming the entry otherwise."""
        if isinstance(value, dict):
            value = [value]
        if isinstance(value, (str, bytes)) or not isinstance(value, Sequence):
            raise ObstacleError(f"obstacles must be a list of segments [[x0, y0], [x1, y1]] or tables "
                                f"{{polygon = [[x, y], ...]}}, got {type(value).__name__}")
        parts = []
        for i, entry in enumerate(value):
            if isinstance(entry, dict):
                keys = set(entry)
                if len(keys) != 1 or not keys <= {"segment", "polygon", "polyline"}:
                    raise ObstacleError(f"obstacles entry {i}: a table needs exactly one of 'segment', "
                                        f"'polygon', 'polyline', got keys {sorted(map(str, keys))}")
                (kind, pts), = entry.items()
                if kind == "segment":
                    parts.append(_as_segments([pts], f"obstacles entry {i} (segment)"))
                else:
                    parts.append(polygon_segments(pts, closed=kind == "polygon", name=f"obstacles entry {i} ({kind})"))
            else:
                parts.append(_as_segments([entry], f"obstacles entry {i}"))
        return cls(np.concatenate(parts) if parts else np.zeros((0, 2, 2)))

    # ---------------------------------------------------------------- properties
    @property
    def m(self) -> int:
        """Number of segments M."""
        return int(self.segments.shape[0])

    def __len__(self) -> int:
        return self.m

    def __bool__(self) -> bool:
        return self.m > 0

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Obstacles):
            return NotImplemented
        return self.segments.shape == other.segments.shape and bool(np.array_equal(self.segments, other.segments))

    def __hash__(self) -> int:
        return hash((self.segments.shape, self.segments.tobytes()))

    def __repr__(self) -> str:
        return f"Obstacles({self.segments.tolist()!r})"

    def to_list(self) -> list[list[list[float]]]:
        """The segments as nested lists ``[[[x0, y0], [x1, y1]], ...]`` (JSON/TOML-able; :meth:`of` reads it back)."""
        return [[[float(v) for v in p] for p in s] for s in self.segments]

    # ---------------------------------------------------------------- validation
    def check_inside(self, bounds: Bounds | tuple[float, float, float, float]) -> Obstacles:
        """Self, or ObstacleError naming the first segment with an end outside ``bounds`` (m)."""
        b = Bounds.of(bounds)
        inside = b.contains(self.segments.reshape(-1, 2)).reshape(-1, 2).all(axis=1)
        bad = np.flatnonzero(~inside)
        if bad.size:
            k = int(bad[0])
            raise ObstacleError(f"obstacle segment {k} {self.segments[k].tolist()} lies outside the arena "
                                f"{tuple(b)}")
        return self

    def check_clear(self, points: ArrayLike, radius: float, what: str) -> Obstacles:
        """Self, or ObstacleError naming the first segment closer than ``radius`` (m) to one of ``points``
        (``(K, 2)`` or ``(K, 3)`` m; ``what`` names them, e.g. "start pose", "charger slot")."""
        p = np.atleast_2d(np.asarray(points, dtype=float))
        if self.m == 0 or p.shape[0] == 0:
            return self
        i, k, d = segments_near(p[:, :2], self.segments, radius)
        hit = d < radius
        if hit.any():
            first = int(np.flatnonzero(hit)[np.lexsort((i[hit], k[hit]))[0]])
            raise ObstacleError(
                f"obstacle segment {int(k[first])} {self.segments[k[first]].tolist()} crosses {what} {int(i[first])} "
                f"at {p[i[first], :2].tolist()} (closer than {radius:g} m: {d[first]:.3f} m)")
        return self


def polygon_segments(vertices: ArrayLike, closed: bool = True, name: str = "polygon") -> NDArray[np.float64]:
    """The edges of a polygon (``closed``, K ≥ 3 vertices) or polyline (K ≥ 2) ``(K, 2)`` m as ``(E, 2, 2)``."""
    try:
        v = np.array(vertices, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ObstacleError(f"{name} must be vertices [[x, y], ...] in m: {exc}") from None
    need = 3 if closed else 2
    if v.ndim != 2 or v.shape[1] != 2 or v.shape[0] < need:
        raise ObstacleError(f"{name} must be at least {need} vertices [[x, y], ...], got shape {v.shape}")
    ends = np.roll(v, -1, axis=0) if closed else v[1:]
    return _as_segments(np.stack([v[: ends.shape[0]], ends], axis=1), name)


def nearest_points(points: NDArray[np.float64], segments: NDArray[np.float64]) -> NDArray[np.float64]:
    """Nearest point of segment ``segments[k]`` (``(K, 2, 2)``) to ``points[k]`` (``(K, 2)``), pairwise, m."""
    a, b = segments[:, 0], segments[:, 1]
    ab = b - a
    num, den = np.einsum("kd,kd->k", points - a, ab), np.einsum("kd,kd->k", ab, ab)
    t = np.divide(num, den, out=np.zeros_like(num), where=den > 0.0)  # a zero-length segment is its end point
    return a + np.clip(t, 0.0, 1.0)[:, None] * ab


def point_segment_distance(points: ArrayLike, segments: ArrayLike) -> NDArray[np.float64]:
    """Euclidean distance (m) from each point ``(N, 2)`` to each segment ``(M, 2, 2)``: ``(N, M)``.

    Dense: for small N·M (tests, validation of a few poses). Per-tick code uses :func:`segments_near`.
    """
    p = np.asarray(points, dtype=float)[:, None, :2]  # (N, 1, 2)
    s = np.asarray(segments, dtype=float)
    a, ab = s[None, :, 0], (s[:, 1] - s[:, 0])[None]  # (1, M, 2)
    num, den = np.sum((p - a) * ab, axis=2), np.broadcast_to(np.sum(ab * ab, axis=2), (p.shape[0], s.shape[0]))
    t = np.clip(np.divide(num, den, out=np.zeros_like(num), where=den > 0.0), 0.0, 1.0)  # zero length: the end
    return np.linalg.norm(p - (a + t[..., None] * ab), axis=2)


def _near_all(p: NDArray[np.float64], s: NDArray[np.float64], radius: float
              ) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
    """:func:`segments_near` for a few points: every (point, segment) on the ``(N, M)`` grid, without gathering
    rows. The arithmetic of :func:`nearest_points` and ``np.linalg.norm`` written out per coordinate (a sum of two
    products, the same bits: tests/core/test_core_obstacles_near_all.py), so the answer is the gathered form's."""
    a, ab = s[:, 0], s[:, 1] - s[:, 0]  # (M, 2)
    abx, aby = ab[:, 0], ab[:, 1]
    den = abx * abx + aby * aby  # (M,)
    px, py = p[:, 0:1], p[:, 1:2]  # (N, 1)
    num = (px - a[:, 0]) * abx + (py - a[:, 1]) * aby  # (N, M)
    t = np.clip(np.divide(num, den, out=np.zeros_like(num), where=den > 0.0), 0.0, 1.0)
    dx = px - (a[:, 0] + t * abx)
    dy = py - (a[:, 1] + t * aby)
    d = np.sqrt(dx * dx + dy * dy)
    i, k = np.nonzero(d <= radius)  # row-major: sorted by (i, k)
    return i.astype(np.int64, copy=False), k.astype(np.int64, copy=False), d[i, k]


def segments_near(points: ArrayLike, segments: ArrayLike, radius: float
                  ) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
    """Every (point i, segment k) within ``radius`` m: ``(i, k, distance)``, sorted by (i, k).

    The spatial query: each segment is cut into pieces of at most 0.25 m and one k-d tree of the
    points answers a ball query per piece (radius + half the piece), so the cost grows with the
    candidate pairs, not with N × M. Exact distances are then computed for the candidates only.
    """
    p = np.asarray(points, dtype=float)[:, :2]
    s = np.asarray(segments, dtype=float)
    empty = (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), np.zeros(0))
    if p.shape[0] == 0 or s.shape[0] == 0:
        return empty
    if p.shape[0] <= DENSE_PAIRS_ROBOTS:  # a few robots: every (point, segment) is a candidate (no k-d tree)
        return _near_all(p, s, radius)
    from scipy.spatial import cKDTree  # here, not at import: core stays light
    length = np.linalg.norm(s[:, 1] - s[:, 0], axis=1)
    pieces = np.maximum(1, np.ceil(length / _PIECE)).astype(np.int64)
    seg_of = np.repeat(np.arange(s.shape[0], dtype=np.int64), pieces)
    frac = (np.arange(seg_of.shape[0]) - np.repeat(np.cumsum(pieces) - pieces, pieces) + 0.5) / pieces[seg_of]
    centres = s[seg_of, 0] + frac[:, None] * (s[seg_of, 1] - s[seg_of, 0])
    reach = radius + 0.5 * length[seg_of] / pieces[seg_of]
    hits = cKDTree(p).query_ball_point(centres, reach)
    counts = np.fromiter((len(h) for h in hits), dtype=np.int64, count=len(hits))
    if counts.sum() == 0:
        return empty
    i = np.fromiter((j for h in hits for j in h), dtype=np.int64, count=int(counts.sum()))
    k = np.repeat(seg_of, counts)
    i, k = np.unique(np.stack([i, k], axis=1), axis=0).T
    d = np.linalg.norm(p[i] - nearest_points(p[i], s[k]), axis=1)
    keep = d <= radius
    return i[keep], k[keep], d[keep]


def segments_cross(a0: ArrayLike, a1: ArrayLike, segments: ArrayLike) -> NDArray[np.bool_]:
    """Whether the moves ``a0 → a1`` (each ``(N, 2)`` m) cross any of ``segments`` ``(M, 2, 2)``: ``(N,)`` bool.

    Proper and touching intersections count (orientation test); dense N × M — for the few robots
    near a segment (the simulator calls it with candidates only)."""
    p, q = np.asarray(a0, dtype=float)[:, None, :2], np.asarray(a1, dtype=float)[:, None, :2]
    s = np.asarray(segments, dtype=float)
    c, d = s[None, :, 0], s[None, :, 1]

    def orient(u: NDArray[np.float64], v: NDArray[np.float64], w: NDArray[np.float64]) -> NDArray[np.float64]:
        return (v[..., 0] - u[..., 0]) * (w[..., 1] - u[..., 1]) - (v[..., 1] - u[..., 1]) * (w[..., 0] - u[..., 0])

    o1, o2 = orient(p, q, c), orient(p, q, d)
    o3, o4 = orient(c, d, p), orient(c, d, q)
    return np.any((o1 * o2 <= 0) & (o3 * o4 <= 0) & ~((o1 == 0) & (o2 == 0)), axis=1)
