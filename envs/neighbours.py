"""Neighbour queries for the learning environments: k-d trees, never an N×N distance matrix.

One swarm: :func:`nearest_neighbours` (the k nearest other robots) and :func:`min_distance`
(the smallest distance between two robots), both O(N log N) with ``scipy.spatial.cKDTree``.

E swarms at once (points ``(E, N, 2)``): one tree over all E·N points lifted to 3-D, swarm e at
height ``e · separation`` with ``separation`` larger than any distance in a swarm, so no query ever
pairs robots of different swarms. Robots of the same swarm differ by exactly 0 in the third
coordinate, so every distance (and every pair within a radius) is bit for bit the one a tree over
that swarm alone computes. :func:`lifted_tree` builds it; :func:`batched_nearest_neighbours` and
:func:`batched_min_distance` use it.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

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
    within the swarm (E, N, k), nearest first."""
    e, n, _ = points.shape
    if k <= 0 or n < 2:
        return np.zeros((e, n, 0)), np.zeros((e, n, 0), dtype=np.intp)
    tree = lifted_tree(points) if tree is None else tree
    dist, idx = tree.query(tree.data, k=k + 1)
    idx = np.asarray(idx, dtype=np.intp).reshape(e * n, k + 1)
    own = np.arange(e * n)
    keep = idx != own[:, None]
    keep[keep.sum(axis=1) > k, -1] = False  # own index absent (a coincident twin came first): drop the last
    others = idx[keep].reshape(e * n, k) - (own // n * n)[:, None]
    return dist.reshape(e * n, k + 1)[keep].reshape(e, n, k), others.reshape(e, n, k)


def batched_nearest_neighbours(points: FloatArray, k: int, tree: cKDTree | None = None) -> IndexArray:
    """(E, N, k) indices (within the swarm) of each robot's k nearest others, nearest first; k ≤ N − 1."""
    return batched_query(points, k, tree)[1]


def batched_min_distance(points: FloatArray, tree: cKDTree | None = None) -> FloatArray:
    """(E,) smallest distance between two robots of each swarm, m (inf for N < 2)."""
    e, n, _ = points.shape
    if n < 2:
        return np.full(e, np.inf)
    return batched_query(points, 1, tree)[0][..., 0].min(axis=1)
