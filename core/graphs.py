"""Interaction graphs for group behaviours, as graph Laplacians and neighbour sets.

Counterparts of ``rps.utilities.graph`` (REFERENCE.md §2) that never modify
their inputs (rps's ``topological_neighbors`` zeroes the caller's diagonal).
A Laplacian is a dense ``(N, N)`` float array L = D − A of an undirected graph.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]

#: robots up to which :func:`pairs_within` compares all pairs (66 at 12: an rps 2.x arena) instead of building a
#: k-d tree — fewer operations at that size, and no scipy import for an rps-sized run
DENSE_PAIRS_ROBOTS = 12


def _upper(n: int) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """``np.triu_indices(n, 1)``, read-only (built once per size at import: the dense paths run on every tick)."""
    i, j = np.triu_indices(n, 1)
    i.flags.writeable = False
    j.flags.writeable = False
    return i, j


_UPPER = tuple(_upper(n) for n in range(DENSE_PAIRS_ROBOTS + 1))


def _all_pairs(p: np.ndarray) -> tuple[NDArray[np.intp], NDArray[np.intp], np.ndarray]:
    """(i, j, squared distance m²) of every pair i < j of ``p`` ``(N, d)``, summed coordinate by coordinate (the
    arithmetic both dense paths share, so they agree with each other to the bit)."""
    n = p.shape[0]
    i, j = _UPPER[n] if n <= DENSE_PAIRS_ROBOTS else np.triu_indices(n, 1)
    e = p[i] - p[j]
    d2 = e[:, 0] * e[:, 0]
    for k in range(1, p.shape[1]):
        d2 = d2 + e[:, k] * e[:, k]
    return i, j, d2


def pairs_within(points: ArrayLike, radius: float) -> NDArray[np.intp]:
    """Pairs ``(K, 2)`` (i < j, sorted by i then j) of ``points`` ``(N, d)`` (m) at most ``radius`` m apart.

    The pairs of ``scipy.spatial.cKDTree(points).query_pairs(radius)``, in key order: all pairs compared
    (the squared distance ``Σ_k (p_ik − p_jk)²``, summed over k in order as the k-d tree does, against ``radius²``)
    up to :data:`DENSE_PAIRS_ROBOTS` robots, the k-d tree above (tests/core/test_core_pairs_within.py checks
    the two agree, boundary distances included).
    """
    p = np.asarray(points, dtype=float)
    n = p.shape[0]
    if n < 2:
        return np.empty((0, 2), dtype=np.intp)
    if n <= DENSE_PAIRS_ROBOTS:
        i, j, d2 = _all_pairs(p)
        keep = d2 <= radius * radius
        return np.stack([i[keep], j[keep]], axis=1).astype(np.intp)
    from scipy.spatial import cKDTree  # lazy: see test_devices_rps_startup_imports

    pairs = cKDTree(p).query_pairs(radius, output_type="ndarray").astype(np.intp)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]


def _check_n(n: int, minimum: int = 1) -> int:
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < minimum:
        raise ValueError(f"number of nodes must be an integer >= {minimum}, got {n!r}")
    return int(n)


def laplacian_from_edges(n: int, edges: ArrayLike) -> FloatArray:
    """Laplacian ``(n, n)`` of the undirected graph with ``edges`` ``(E, 2)`` (int node pairs)."""
    n = _check_n(n)
    e = np.asarray(edges, dtype=np.intp).reshape(-1, 2)
    if e.size and (e.min() < 0 or e.max() >= n):
        raise ValueError(f"edge endpoints must be in 0..{n - 1}")
    if np.any(e[:, 0] == e[:, 1]):
        raise ValueError("self-loops are not allowed in an interaction graph")
    a = np.zeros((n, n))
    a[e[:, 0], e[:, 1]] = 1.0
    a[e[:, 1], e[:, 0]] = 1.0
    return np.diag(a.sum(axis=1)) - a


def edges_of(laplacian: ArrayLike) -> NDArray[np.intp]:
    """Edges ``(E, 2)`` with i < j of the graph whose Laplacian is given."""
    L = np.asarray(laplacian, dtype=float)
    i, j = np.nonzero(np.triu(L, 1) != 0)
    return np.column_stack((i, j)).astype(np.intp)


def cycle_laplacian(n: int) -> FloatArray:
    """Cycle graph C_n (rps ``cycle_GL``); a single edge for n = 2."""
    n = _check_n(n, 2)
    i = np.arange(n)
    edges = np.column_stack((i, (i + 1) % n))
    return laplacian_from_edges(n, np.unique(np.sort(edges, axis=1), axis=0))


def line_laplacian(n: int) -> FloatArray:
    """Path graph P_n (rps ``lineGL``)."""
    n = _check_n(n)
    i = np.arange(n - 1)
    return laplacian_from_edges(n, np.column_stack((i, i + 1)))


def complete_laplacian(n: int) -> FloatArray:
    """Complete graph K_n (rps ``completeGL``)."""
    n = _check_n(n)
    return n * np.eye(n) - np.ones((n, n))


def random_connected_laplacian(n: int, extra_edges: int, rng: np.random.Generator | int | None = None) -> FloatArray:
    """A random connected graph: a random spanning tree plus ``extra_edges`` random edges (rps ``random_connectedGL``)."""
    n = _check_n(n)
    rng = np.random.default_rng(rng)
    order = rng.permutation(n)
    parents = order[rng.integers(0, np.maximum(np.arange(1, n), 1))] if n > 1 else np.empty(0, dtype=int)
    tree = np.column_stack((order[1:], parents)) if n > 1 else np.empty((0, 2), dtype=int)
    L = laplacian_from_edges(n, tree)
    missing = np.column_stack(np.nonzero(np.triu(L == 0, 1)))
    k = min(max(int(extra_edges), 0), len(missing))
    if k:
        add = missing[rng.choice(len(missing), size=k, replace=False)]
        L = laplacian_from_edges(n, np.vstack((edges_of(L), add)))
    return L


def topological_neighbors(laplacian: ArrayLike, agent: int) -> NDArray[np.intp]:
    """Neighbours of ``agent`` in the graph (rps ``topological_neighbors``, without mutating L)."""
    L = np.asarray(laplacian, dtype=float)
    if not 0 <= agent < L.shape[0]:
        raise ValueError(f"agent must be in 0..{L.shape[0] - 1}, got {agent}")
    row = L[agent].copy()
    row[agent] = 0.0
    return np.flatnonzero(row != 0).astype(np.intp)


def nearest_pair_distance(points: ArrayLike) -> float:
    """Smallest distance (m) between two of ``points`` ``(N, d)``, N ≥ 2: all pairs compared up to
    :data:`DENSE_PAIRS_ROBOTS` robots (the same squared sums as :func:`pairs_within`), a k-d tree above; the same
    number either way (the square root is monotone and correctly rounded)."""
    p = np.asarray(points, dtype=float)
    n = p.shape[0]
    if n < 2:
        raise ValueError(f"the nearest pair needs at least 2 points, got {n}")
    if n <= DENSE_PAIRS_ROBOTS:
        return float(np.sqrt(_all_pairs(p)[2].min()))
    from scipy.spatial import cKDTree  # lazy: see test_devices_rps_startup_imports

    return float(cKDTree(p).query(p, k=2)[0][:, 1].min())


def delta_disk_laplacian(positions: ArrayLike, delta: float) -> FloatArray:
    """Laplacian of the δ-disk proximity graph of ``positions`` ``(N, 2)``: i ~ j iff ‖p_i − p_j‖ ≤ δ."""
    p = np.asarray(positions, dtype=float)
    if not delta > 0:
        raise ValueError(f"delta must be > 0 m, got {delta!r}")
    return laplacian_from_edges(len(p), pairs_within(p[:, :2], delta))


def delta_disk_neighbors(positions: ArrayLike, agent: int, delta: float) -> NDArray[np.intp]:
    """Agents within ``delta`` m of ``agent`` (rps ``delta_disk_neighbors``)."""
    p = np.asarray(positions, dtype=float)
    d = np.linalg.norm(p[:, :2] - p[agent, :2], axis=1)
    d[agent] = np.inf
    return np.flatnonzero(d <= delta).astype(np.intp)


def rigid_formation(n_sides: int = 6, edge_length: float = 0.4) -> tuple[FloatArray, NDArray[np.intp], FloatArray]:
    """A minimally-rigid formation on a regular polygon: (shape ``(n, 2)``, edges ``(2n−3, 2)``, desired lengths).

    The polygon's sides plus a fan of diagonals from vertex 0 give 2n − 3
    edges, which is generically (Laman) rigid in the plane, so distance
    constraints fix the shape up to rigid motion and reflection.
    """
    n = _check_n(n_sides, 3)
    ang = 2 * np.pi * np.arange(n) / n
    radius = edge_length / (2 * np.sin(np.pi / n))
    shape = radius * np.column_stack((np.cos(ang), np.sin(ang)))
    sides = np.column_stack((np.arange(n), (np.arange(n) + 1) % n))
    diagonals = np.column_stack((np.zeros(n - 3, dtype=int), np.arange(2, n - 1)))
    edges = np.sort(np.vstack((sides, diagonals)), axis=1).astype(np.intp)
    lengths = np.linalg.norm(shape[edges[:, 0]] - shape[edges[:, 1]], axis=1)
    return shape, edges, lengths
