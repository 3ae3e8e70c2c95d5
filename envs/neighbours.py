"""Neighbour queries for the learning environments: k-d trees, never an N×N distance matrix.

One swarm: :func:`nearest_neighbours` (the k nearest other robots) and :func:`min_distance`
(the smallest distance between two robots), both O(N log N) with ``scipy.spatial.cKDTree``.

E swarms at once (points ``(E, N, 2)``): one tree over all E·N points lifted to 3-D, swarm e at
height ``e · separation`` with ``separation`` larger than any distance in a swarm, so no query ever
pairs robots of different swarms. Robots of the same swarm differ by exactly 0 in the third
coordinate, so every distance (and every pair within a radius) is bit for bit the one a tree over
that swarm alone computes. :func:`lifted_tree` builds it.

With numba (:mod:`swarmdeck.core.compiled`; calls on fewer than ``batched_kernels.COMPILED_FROM`` robots only once
numba is imported) the batched queries need no tree: one compiled call sweeps every swarm
along its wider axis (sorted once, scanning outwards until the gap alone exceeds the k-th distance or the radius),
O(N log N + N·s) per swarm for s robots in the strip, no N×N array, and the same answers bit for bit as the tree
(squared distances dx·dx + dy·dy, the square root at the end, as ``cKDTree``; ties by the lower index, as a stable
sort): :func:`batched_query` (k nearest, distances) and :func:`swarm_pairs` (pairs within a radius, what
``cKDTree.query_pairs`` returns; :class:`SwarmPairs` offers it under that name for
:func:`swarmdeck.safety.constraints.pair_rows`). Without numba both fall back to :func:`lifted_tree`.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from swarmdeck.core.compiled import jit
from swarmdeck.envs.batched_kernels import use_compiled

FloatArray = NDArray[np.float64]
IndexArray = NDArray[np.intp]


def nearest_neighbours(points: FloatArray, k: int) -> IndexArray:
    """(N, k) indices of each point's k nearest other points (N, 2 in m), nearest first (k ≤ N − 1)."""
    n = len(points)
    if k <= 0 or n < 2:
        return np.zeros((n, 0), dtype=np.intp)
    _, idx = cKDTree(points).query(points, k=k + 1)
    return _drop_self(np.asarray(idx, dtype=np.intp).reshape(n, k + 1), np.arange(n), k)


def _drop_self(idx: IndexArray, own: IndexArray, k: int) -> IndexArray:
    """Each row of ``idx`` (M, k+1) without the point's own index ``own`` (M,) (found first unless a
    coincident point comes first), the first k others kept in order."""
    keep = idx != own[:, None]
    keep[keep.sum(axis=1) > k, -1] = False  # own index absent (a coincident twin came first): drop the last
    return idx[keep].reshape(len(idx), k)


def min_distance(points: FloatArray) -> float:
    """Smallest distance between two of the points (N, 2), m; inf for fewer than two."""
    if len(points) < 2:
        return float("inf")
    d, _ = cKDTree(points).query(points, k=2)
    return float(np.min(d[:, 1]))


def lifted_tree(points: FloatArray) -> cKDTree:
    """One k-d tree over E swarms ``(E, N, 2)`` (module docstring): swarm e lifted to z = e·separation."""
    e, n, _ = points.shape
    flat = points.reshape(e * n, 2)
    reach = float(np.abs(flat).max()) if flat.size else 0.0  # every swarm within [-reach, reach]²
    if not np.isfinite(reach):
        raise ValueError("lifted_tree: points must be finite")
    separation = 4.0 * (reach + 1.0)
    z = np.repeat(np.arange(e, dtype=float) * separation, n)
    return cKDTree(np.column_stack((flat, z)))


def batched_query(points: FloatArray, k: int, tree: cKDTree | None = None) -> tuple[FloatArray, IndexArray]:
    """Each robot's k nearest others in its swarm (points (E, N, 2), k ≤ N − 1): distances (E, N, k) m and indices
    within the swarm (E, N, k), nearest first. ``tree``: a :func:`lifted_tree` of the points to query (None: the
    compiled sweep when numba is installed, else a new tree); the answers are the same either way."""
    e, n, _ = points.shape
    if k <= 0 or n < 2:
        return np.zeros((e, n, 0)), np.zeros((e, n, 0), dtype=np.intp)
    if tree is None and use_compiled(e * n):
        flat = _finite_flat(points, "batched_query")
        dist = np.empty((e * n, k))
        idx = np.empty((e * n, k), dtype=np.intp)
        _knn_sweep(flat, e, n, k, dist, idx)
        return dist.reshape(e, n, k), idx.reshape(e, n, k)
    tree = lifted_tree(points) if tree is None else tree
    dist, idx = tree.query(tree.data, k=k + 1)
    idx = np.asarray(idx, dtype=np.intp).reshape(e * n, k + 1)
    own = np.arange(e * n)
    keep = idx != own[:, None]
    keep[keep.sum(axis=1) > k, -1] = False  # own index absent (a coincident twin came first): drop the last
    others = idx[keep].reshape(e * n, k) - (own // n * n)[:, None]
    return dist.reshape(e * n, k + 1)[keep].reshape(e, n, k), others.reshape(e, n, k)


def _finite_flat(points: FloatArray, who: str) -> FloatArray:
    """points (E, N, 2) as one C-contiguous float (E·N, 2) array; ValueError naming ``who`` if any is NaN or inf."""
    e, n, _ = points.shape
    flat = np.ascontiguousarray(points, dtype=float).reshape(e * n, 2)
    if not np.isfinite(flat).all():
        raise ValueError(f"{who}: points must be finite")
    return flat


def swarm_pairs(points: FloatArray, radius: float) -> IndexArray:
    """(M, 2) pairs of robots of the same swarm at most ``radius`` m apart (points (E, N, 2)), as flattened indices
    e·N + i, each pair once with the lower index first (order unspecified) — ``lifted_tree(points).query_pairs``."""
    e, n, _ = points.shape
    if n < 2:
        return np.zeros((0, 2), dtype=np.intp)
    if not use_compiled(e * n):
        return np.asarray(lifted_tree(points).query_pairs(radius, output_type="ndarray"), dtype=np.intp)
    flat = _finite_flat(points, "swarm_pairs")
    r2 = float(radius) * float(radius)
    out = np.empty((4 * e * n, 2), dtype=np.intp)
    count = _pairs_sweep(flat, e, n, r2, out)
    if count > out.shape[0]:  # denser than guessed: once more with room for all
        out = np.empty((count, 2), dtype=np.intp)
        _pairs_sweep(flat, e, n, r2, out)
    return out[:count]


class SwarmPairs:
    """E swarms' points (E, N, 2) answering ``query_pairs(r, output_type="ndarray")`` like a :func:`lifted_tree`
    (by :func:`swarm_pairs`), for :func:`swarmdeck.safety.constraints.pair_rows`."""

    def __init__(self, points: FloatArray) -> None:
        self.points = points

    def query_pairs(self, r: float, output_type: str = "ndarray") -> IndexArray:
        """The pairs within ``r`` m (:func:`swarm_pairs`); only ``output_type="ndarray"``."""
        if output_type != "ndarray":
            raise ValueError(f"SwarmPairs.query_pairs: only output_type='ndarray', got {output_type!r}")
        return swarm_pairs(self.points, r)


def batched_nearest_neighbours(points: FloatArray, k: int, tree: cKDTree | None = None) -> IndexArray:
    """(E, N, k) indices (within the swarm) of each robot's k nearest others, nearest first; k ≤ N − 1."""
    return batched_query(points, k, tree)[1]


def batched_min_distance(points: FloatArray, tree: cKDTree | None = None) -> FloatArray:
    """(E,) smallest distance between two robots of each swarm, m (inf for N < 2)."""
    e, n, _ = points.shape
    if n < 2:
        return np.full(e, np.inf)
    return batched_query(points, 1, tree)[0][..., 0].min(axis=1)


# ---------------------------------------------------------------------------- compiled sweeps (one call for E swarms)
_BRUTE = 24  # robots per swarm up to which the k-nearest scan visits every other robot instead of sorting (faster)

@jit
def _sweep_axis(points, base, n):  # pragma: no cover - compiled
    """0 (x) or 1 (y): the axis along which swarm rows ``base … base + n`` spread more (the sweep's axis)."""
    lo0 = hi0 = points[base, 0]
    lo1 = hi1 = points[base, 1]
    for i in range(base + 1, base + n):
        lo0 = min(lo0, points[i, 0])
        hi0 = max(hi0, points[i, 0])
        lo1 = min(lo1, points[i, 1])
        hi1 = max(hi1, points[i, 1])
    return 0 if hi0 - lo0 >= hi1 - lo1 else 1
@jit
def _knn_sweep(points, n_swarms, n, k, dist, idx):  # pragma: no cover - compiled
    """Each robot's k nearest others of its swarm by a sweep along the axis of larger spread (points (E·N, 2), swarm e = rows e·N …):
    writes dist (E·N, k) m and idx (E·N, k) within the swarm; ties by the lower index."""
    bd = np.empty(k)
    bi = np.empty(k, dtype=np.int64)
    order = np.arange(n)
    rank = np.arange(n)
    for e in range(n_swarms):
        base = e * n
        ax = _sweep_axis(points, base, n)
        if n > _BRUTE:  # few robots: scan them all (no sort), every one is within the "strip"
            order = np.argsort(points[base:base + n, ax], kind="mergesort")
            for r in range(n):
                rank[order[r]] = r
        for i in range(n):
            xi = points[base + i, 0]
            yi = points[base + i, 1]
            for h in range(k):
                bd[h] = np.inf
                bi[h] = n
            for direction in (1, -1):
                r = rank[i] + direction
                while 0 <= r < n:
                    q = order[r]
                    dx = xi - points[base + q, 0]
                    dy = yi - points[base + q, 1]
                    d2 = dx * dx + dy * dy
                    gap = dx if ax == 0 else dy
                    if n > _BRUTE and gap * gap > bd[k - 1]:
                        break
                    if d2 < bd[k - 1] or (d2 == bd[k - 1] and q < bi[k - 1]):
                        p = k - 1
                        while p > 0 and (bd[p - 1] > d2 or (bd[p - 1] == d2 and bi[p - 1] > q)):
                            bd[p] = bd[p - 1]
                            bi[p] = bi[p - 1]
                            p -= 1
                        bd[p] = d2
                        bi[p] = q
                    r += direction
            for h in range(k):
                dist[base + i, h] = np.sqrt(bd[h])
                idx[base + i, h] = bi[h]


@jit
def _pairs_sweep(points, n_swarms, n, r2, out):  # pragma: no cover - compiled
    """Pairs (global indices, i < j) of the same swarm with squared distance ≤ r2, by the same sweep; writes at most
    len(out) of them into out (M, 2) and returns how many there are (call again with a larger ``out`` if more)."""
    count = 0
    cap = out.shape[0]
    for e in range(n_swarms):
        base = e * n
        ax = _sweep_axis(points, base, n)
        order = np.argsort(points[base:base + n, ax], kind="mergesort")
        for r in range(n):
            a = order[r]
            xa = points[base + a, 0]
            ya = points[base + a, 1]
            for s in range(r + 1, n):
                b = order[s]
                dx = xa - points[base + b, 0]
                dy = ya - points[base + b, 1]
                gap = dx if ax == 0 else dy
                if gap * gap > r2:
                    break
                if dx * dx + dy * dy <= r2:
                    if count < cap:
                        lo = a if a < b else b
                        out[count, 0] = base + lo
                        out[count, 1] = base + a + b - lo
                    count += 1
    return count
