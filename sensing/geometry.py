"""Exact ray casts: the first hit of many rays against circles (robots' bodies), line segments (obstacles) and the
arena's walls, vectorised over rays (no per-robot Python loop, no N×N matrix).

Circles are found through a k-d tree in stages of growing reach: a ray whose first hit lies within the stage's
reach is final (every circle it could hit earlier has its centre within reach + radius of the origin, so it was a
candidate); only the rays still open go on to the next, longer stage. On a crowded floor most rays end in the
first stage; on a sparse one there are few candidates anyway.

Units m. A ray is an origin ``(2,)`` and a unit direction ``(2,)``; its distance ``t`` is along the direction.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.bounds import Bounds
from swarmdeck.core.graphs import DENSE_PAIRS_ROBOTS, pairs_within
from swarmdeck.sensing import kernels
from swarmdeck.sensing.config import SensingConfigError

__all__ = ["cast_rays", "cast_sensor_rays", "check_segments", "ray_box", "ray_circles", "ray_segments",
           "segments_and_walls"]

FloatArray = NDArray[np.float64]
#: Below this |cross(ray, segment)| a ray and a segment are parallel: no single crossing point.
_PARALLEL = 1e-12
#: The stages' reach as fractions of the range (the last is the whole range).
_STAGES = (0.125, 0.375, 1.0)
#: The same for :func:`cast_sensor_rays`, whose stages work on robots (open while any of its rays is).
_SENSOR_STAGES = (0.25, 1.0)
#: Up to this many (ray, segment) pairs :func:`ray_segments` takes its numpy form even where numba is installed:
#: the same bits (tests/sensing/test_sensing_small_paths.py), no numba import (≈ 0.5-1 s of CPU) for an rps-sized
#: run (84 rays of 12 robots × 48 segments).
SMALL_RAY_SEGMENTS = 4096


def check_segments(segments: ArrayLike | None, name: str = "obstacles") -> FloatArray:
    """``segments`` (an array, or an object with a ``segments`` array such as ``core.obstacles.Obstacles``) as a
    finite ``(M, 2, 2)`` float array (``[k, 0]`` one end, ``[k, 1]`` the other), or an empty one for None; raises :class:`~swarmdeck.sensing.config.SensingConfigError` naming what is wrong."""
    if segments is None:
        return np.empty((0, 2, 2))
    segments = getattr(segments, "segments", segments)  # an obstacles object holding its (M, 2, 2) segments
    arr = np.asarray(segments)
    if arr.size == 0:
        return np.empty((0, 2, 2))
    if arr.dtype.kind not in "fiu" or arr.dtype == bool:
        raise SensingConfigError(f"{name} must be a numeric (M, 2, 2) array of segment end points, got dtype {arr.dtype}")
    if arr.ndim != 3 or arr.shape[1:] != (2, 2):
        raise SensingConfigError(f"{name} must have shape (M, 2, 2) (M segments, 2 ends, x and y), got {arr.shape}")
    arr = arr.astype(float)
    bad = ~np.isfinite(arr).all(axis=(1, 2))
    if bad.any():
        raise SensingConfigError(f"{name}: segment(s) {np.flatnonzero(bad).tolist()} have NaN or infinite coordinates")
    return arr


def ray_segments(origins: FloatArray, directions: FloatArray, segments: FloatArray) -> FloatArray:
    """Distance ``(R,)`` along each ray to the first segment it crosses (ends included), inf if none.

    Solves o + t·u = p + s·(q − p) with t ≥ 0, 0 ≤ s ≤ 1 for every ray and segment (R·M work; obstacles are few).
    A ray parallel to a segment never hits it (as rps 2.0).
    """
    out = np.full(len(origins), np.inf)
    if len(segments) == 0 or len(origins) == 0:
        return out
    if kernels.AVAILABLE and len(origins) * len(segments) > SMALL_RAY_SEGMENTS:
        kernels.call(kernels.segment_hits, np.ascontiguousarray(origins, dtype=float),
                     np.ascontiguousarray(directions, dtype=float), np.ascontiguousarray(segments, dtype=float),
                     _PARALLEL, out)
        return out
    p = segments[:, 0]  # (M, 2)
    d = segments[:, 1] - p  # (M, 2)
    ux, uy = directions[:, 0:1], directions[:, 1:2]  # (R, 1)
    wx = p[None, :, 0] - origins[:, 0:1]  # (R, M)
    wy = p[None, :, 1] - origins[:, 1:2]
    denom = ux * d[None, :, 1] - uy * d[None, :, 0]
    ok = np.abs(denom) > _PARALLEL
    safe = np.where(ok, denom, 1.0)
    t = (wx * d[None, :, 1] - wy * d[None, :, 0]) / safe
    s = (wx * uy - wy * ux) / safe
    hit = ok & (t >= 0.0) & (s >= 0.0) & (s <= 1.0)
    return np.where(hit, t, np.inf).min(axis=1)


def ray_box(origins: FloatArray, directions: FloatArray, bounds: Bounds) -> FloatArray:
    """Distance ``(R,)`` from origins inside the rectangle to its walls along each ray (0 for an origin outside)."""
    x0, x1, y0, y1 = bounds
    ox, oy = origins[:, 0], origins[:, 1]
    ux, uy = directions[:, 0], directions[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        tx = np.where(ux > 0, (x1 - ox) / ux, np.where(ux < 0, (x0 - ox) / ux, np.inf))
        ty = np.where(uy > 0, (y1 - oy) / uy, np.where(uy < 0, (y0 - oy) / uy, np.inf))
    return np.maximum(np.minimum(tx, ty), 0.0)


def ray_circles(origins: FloatArray, directions: FloatArray, rays: NDArray[np.intp], centres: FloatArray,
                circles: NDArray[np.intp], radius: float) -> FloatArray:
    """Distance along ray ``rays[k]`` to circle ``circles[k]`` (``(P,)``), inf where it misses or lies behind.

    An origin inside a circle reads 0 (the sensor is against the body).
    """
    o = origins[rays]
    u = directions[rays]
    w = centres[circles] - o
    b = np.einsum("ij,ij->i", w, u)
    c = np.einsum("ij,ij->i", w, w) - radius * radius
    disc = b * b - c
    hit = (disc >= 0.0) & (b >= 0.0)
    t = b - np.sqrt(np.maximum(disc, 0.0))
    t = np.where(c <= 0.0, 0.0, t)
    return np.where(hit | (c <= 0.0), t, np.inf)


def _first_circle_hits(origins: FloatArray, directions: FloatArray, max_range: float, centres: FloatArray,
                       radius: float, owners: NDArray[np.intp] | None) -> FloatArray:
    """Distance ``(R,)`` to the first circle along each ray within ``max_range`` (inf if none), staged k-d tree."""
    n_rays = len(origins)
    best = np.full(n_rays, np.inf)
    if n_rays == 0 or len(centres) == 0:
        return best
    from scipy.spatial import cKDTree  # lazy: see test_devices_rps_startup_imports

    tree = cKDTree(centres)
    open_rays = np.arange(n_rays)
    for frac in _STAGES:
        reach = max_range * frac
        sub = cKDTree(origins[open_rays])
        pairs = sub.sparse_distance_matrix(tree, reach + radius, output_type="ndarray")
        if len(pairs):
            rays = open_rays[pairs["i"].astype(np.intp)]
            circles = pairs["j"].astype(np.intp)
            if owners is not None:
                keep = owners[rays] != circles
                rays, circles = rays[keep], circles[keep]
            t = ray_circles(origins, directions, rays, centres, circles, radius)
            np.minimum.at(best, rays, t)
        done = best[open_rays] <= reach
        open_rays = open_rays[~done]
        if len(open_rays) == 0:
            break
    best[best > max_range] = np.inf
    return best


def _dense_pair_circle_hits(centres: FloatArray, origins: FloatArray, directions: FloatArray,
                            pairs: NDArray[np.intp], radius: float, k: int) -> FloatArray:
    """:func:`kernels.pair_circle_hits` in numpy, for a few robots: the K rays of each robot of every pair
    ``(P, 2)`` (both directions) against the other's circle; ``(N·K,)`` first hits, inf where none. Every (robot,
    body, sensor) of the ``(N, N, K)`` grid is computed with the kernel's arithmetic in its order, those of no pair
    are dropped — so the same bits (a NaN never lowers a hit, as the kernel's ``t < best``)."""
    n = len(centres)
    if not len(pairs):
        return np.full(n * k, np.inf)
    o = origins.reshape(n, 1, k, 2)  # [a, ·, sensor]
    u = directions.reshape(n, 1, k, 2)
    paired = np.zeros((n, n, 1), dtype=bool)  # [a, b]: b is within reach of a
    paired[pairs[:, 0], pairs[:, 1]] = True
    paired[pairs[:, 1], pairs[:, 0]] = True
    with np.errstate(invalid="ignore", over="ignore"):
        wx = centres[None, :, 0, None] - o[..., 0]  # (N, N, K): body b's centre from a's sensor
        wy = centres[None, :, 1, None] - o[..., 1]
        bb = wx * u[..., 0] + wy * u[..., 1]
        cc = (wx * wx + wy * wy) - radius * radius
        disc = bb * bb - cc
        t = np.where(cc <= 0.0, 0.0, np.where((bb < 0.0) | (disc < 0.0), np.inf, bb - np.sqrt(disc)))
        t = np.where(paired & (t < np.inf), t, np.inf)
    return t.min(axis=1).reshape(-1)


def cast_sensor_rays(centres: ArrayLike, headings: ArrayLike, origins: ArrayLike, directions: ArrayLike,
                     sensor_headings: ArrayLike, max_range: float, radius: float) -> FloatArray:
    """The first hit ``(N, K)`` m of each robot's K sensor rays against the other robots' bodies (circles of
    ``radius`` around ``centres`` ``(N, 2)``); inf where none lies within ``max_range``.

    The rays of robot a start ``origins[a]`` ``(K, 2)`` within a mount radius m of ``centres[a]`` and point at
    ``headings[a] + sensor_headings`` (``directions`` ``(N, K, 2)``). Candidates are robot pairs from a k-d tree
    (in two stages: near pairs first; a far pair is kept only while some ray of its robot has found nothing
    closer); of a pair (a, b) at centre distance d only the sensors
    whose heading lies within asin((radius + m)/d) of the direction from a to b can hit b (every sensor when
    d ≤ 2(radius + m)), found by a binary search over the sorted sensor headings — so the exact ray–circle test
    runs on a few (pair, sensor) candidates, not on every pair times K. Up to
    :data:`~swarmdeck.core.graphs.DENSE_PAIRS_ROBOTS` robots (an rps arena: 84 rays, 11 bodies each) every sensor of
    every pair within reach (:func:`~swarmdeck.core.graphs.pairs_within`, all pairs compared) is tested in numpy: the
    compiled kernel's bits, without scipy or numba.
    """
    c = np.asarray(centres, dtype=float).reshape(-1, 2)
    th = np.asarray(headings, dtype=float).reshape(-1)
    o = np.asarray(origins, dtype=float)
    u = np.asarray(directions, dtype=float)
    h = np.mod(np.asarray(sensor_headings, dtype=float).reshape(-1), 2 * np.pi)
    n, k = o.shape[0], o.shape[1]
    best = np.full(n * k, np.inf)
    if n < 2:
        return best.reshape(n, k)
    mount = float(np.max(np.hypot(*(o - c[:, None, :]).reshape(-1, 2).T))) if n else 0.0
    o_flat, u_flat = o.reshape(-1, 2), u.reshape(-1, 2)
    near = radius + mount
    if n <= DENSE_PAIRS_ROBOTS:  # a few robots: every pair within reach, every sensor, in numpy (no scipy, no numba)
        best = _dense_pair_circle_hits(c, o_flat, u_flat, pairs_within(c, max_range + near), float(radius), k)
        best[best > max_range] = np.inf
        return best.reshape(n, k)
    order = np.argsort(h, kind="stable")  # the numpy fallback's angular windows
    sorted_h = h[order]
    twice = np.concatenate((sorted_h, sorted_h + 2 * np.pi))
    from scipy.spatial import cKDTree  # lazy: see test_devices_rps_startup_imports

    tree = cKDTree(c)
    if kernels.AVAILABLE:  # compiled: every sensor of every pair within reach, one loop
        pairs = tree.query_pairs(max_range + near, output_type="ndarray").astype(np.intp)
        a = np.ascontiguousarray(np.concatenate((pairs[:, 0], pairs[:, 1])))
        b = np.ascontiguousarray(np.concatenate((pairs[:, 1], pairs[:, 0])))
        kernels.call(kernels.pair_circle_hits, a, b, np.ascontiguousarray(o_flat), np.ascontiguousarray(u_flat), c,
                     float(radius), k, best)
        best[best > max_range] = np.inf
        return best.reshape(n, k)
    done_within = 0.0  # pairs closer than this (centre distance) were tested already
    for frac in _SENSOR_STAGES:
        reach = max_range * frac + near
        pairs = tree.query_pairs(reach, output_type="ndarray").astype(np.intp)
        a = np.concatenate((pairs[:, 0], pairs[:, 1]))
        b = np.concatenate((pairs[:, 1], pairs[:, 0]))
        rel = c[b] - c[a]
        d = np.hypot(rel[:, 0], rel[:, 1])
        # a pair can still matter only if it is new and some ray of a has found nothing closer than b can be
        open_to = best.reshape(n, k).max(axis=1)
        keep = (d > done_within) & (d - near < open_to[a])
        a, b, d, rel = a[keep], b[keep], d[keep], rel[keep]
        done_within = reach
        if not len(a):
            continue
        phi = np.arctan2(rel[:, 1], rel[:, 0]) - th[a]
        close = d <= 2 * near
        alpha = np.where(close, np.pi, np.arcsin(np.minimum(near / np.maximum(d, near), 1.0)) + 1e-9)
        start = np.mod(phi - alpha, 2 * np.pi)
        lo = np.searchsorted(twice, start, side="left")
        hi = np.searchsorted(twice, start + 2 * alpha, side="right")
        count = np.where(close, k, np.minimum(hi - lo, k))
        lo = np.where(close, 0, lo)
        total = int(count.sum())
        if not total:
            continue
        pair = np.repeat(np.arange(len(a)), count)
        first = np.cumsum(count) - count
        slot = lo[pair] + (np.arange(total) - first[pair])
        rays = a[pair] * k + order[slot % k]
        t = ray_circles(o_flat, u_flat, rays, c, b[pair], radius)
        np.minimum.at(best, rays, t)
    best[best > max_range] = np.inf
    return best.reshape(n, k)


def cast_rays(origins: ArrayLike, directions: ArrayLike, max_range: float, *, centres: ArrayLike | None = None,
              radius: float = 0.0, owners: ArrayLike | None = None, segments: ArrayLike | None = None,
              bounds: Bounds | None = None) -> FloatArray:
    """The exact first hit along each ray, m: ``(R,)``, inf where nothing lies within ``max_range``.

    Args:
        origins: ``(R, 2)`` ray origins, m.
        directions: ``(R, 2)`` unit directions.
        max_range: the rays' length, m (> 0).
        centres: ``(N, 2)`` centres of circles of ``radius`` m (the robots' bodies), or None.
        owners: ``(R,)`` index into ``centres`` of the circle each ray starts from (never hit by its own ray).
        segments: ``(M, 2, 2)`` line segments (obstacles), or None.
        bounds: the arena rectangle whose walls stop the rays, or None (an open floor).
    """
    o = np.asarray(origins, dtype=float).reshape(-1, 2)
    u = np.asarray(directions, dtype=float).reshape(-1, 2)
    if u.shape != o.shape:
        raise ValueError(f"directions {u.shape} must match origins {o.shape}")
    if not (np.isfinite(max_range) and max_range > 0):
        raise ValueError(f"max_range must be a finite number > 0 m, got {max_range!r}")
    best = np.full(len(o), np.inf)
    if centres is not None:
        c = np.asarray(centres, dtype=float).reshape(-1, 2)
        own = None if owners is None else np.asarray(owners, dtype=np.intp).reshape(-1)
        best = _first_circle_hits(o, u, max_range, c, float(radius), own)
    return segments_and_walls(best, o, u, max_range, check_segments(segments), bounds)


def segments_and_walls(best: FloatArray, origins: FloatArray, directions: FloatArray, max_range: float,
                       segments: FloatArray, bounds: Bounds | None) -> FloatArray:
    """``best`` ``(R,)`` m lowered to each ray's first crossing of ``segments`` (checked ``(M, 2, 2)``, see
    :func:`check_segments`) and of the walls of ``bounds`` (None: none), then inf beyond ``max_range``: the end of
    :func:`cast_rays`, for callers that checked their rays and segments once (:class:`~swarmdeck.sensing.Sensors`).
    Returns a new array."""
    out = best
    if len(segments):
        out = np.minimum(out, ray_segments(origins, directions, segments))
    if bounds is not None:
        out = np.minimum(out, ray_box(origins, directions, Bounds.of(bounds)))
    if out is best:
        out = best.copy()
    out[out > max_range] = np.inf
    return out
