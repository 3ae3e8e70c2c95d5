"""Who can hear whom: a fixed graph, the Δ-disk or the k nearest (REFERENCE.md §16).

A topology maps the robots' positions ``(N, 2)`` (m) to the directed links ``(E, 2)`` (int: sender,
receiver) that exist this tick, sorted by sender then receiver, with no self-links. The proximity
topologies use a k-d tree (``scipy.spatial.cKDTree``), never an N × N distance matrix.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.graphs import edges_of

__all__ = ["DiskTopology", "FixedTopology", "KNearestTopology", "Topology", "sorted_links"]

Links = NDArray[np.intp]


@runtime_checkable
class Topology(Protocol):
    """Anything with ``links(positions (N, 2)) -> (E, 2)`` directed, sorted, self-link-free."""

    def links(self, positions: NDArray[np.float64]) -> Links: ...


def sorted_links(links: ArrayLike) -> Links:
    """Unique directed links ``(E, 2)`` sorted by sender, then receiver."""
    e = np.asarray(links, dtype=np.intp).reshape(-1, 2)
    if not len(e):
        return np.empty((0, 2), dtype=np.intp)
    return np.unique(e, axis=0)


@dataclass(frozen=True)
class FixedTopology:
    """The paper's graph G: undirected ``edges`` ``(E, 2)``, links both ways, whatever the positions.

    Build it from a Laplacian with :meth:`from_laplacian` (``core.graphs`` makes the usual ones).
    """

    edges: tuple[tuple[int, int], ...]

    def __post_init__(self) -> None:
        for e in self.edges:
            if len(e) != 2 or e[0] == e[1] or min(e) < 0:
                raise ValueError(f"FixedTopology: edge {e!r} must join two different robots (ids >= 0)")

    @classmethod
    def from_edges(cls, edges: ArrayLike) -> FixedTopology:
        e = np.asarray(edges, dtype=np.intp).reshape(-1, 2)
        return cls(tuple((int(a), int(b)) for a, b in e))

    @classmethod
    def from_laplacian(cls, laplacian: ArrayLike) -> FixedTopology:
        return cls.from_edges(edges_of(laplacian))

    def links(self, positions: NDArray[np.float64]) -> Links:
        n = len(positions)
        e = np.asarray(self.edges, dtype=np.intp).reshape(-1, 2)
        if len(e) and e.max() >= n:
            raise ValueError(f"FixedTopology: an edge names robot {int(e.max())}, but there are {n} robots")
        return sorted_links(np.vstack((e, e[:, ::-1])))


@dataclass(frozen=True)
class DiskTopology:
    """Δ-disk: i and j hear each other when ‖p_i − p_j‖ ≤ ``delta`` (m)."""

    delta: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.delta) and self.delta > 0):
            raise ValueError(f"DiskTopology: delta must be a positive distance in metres, got {self.delta!r}")

    def links(self, positions: NDArray[np.float64]) -> Links:
        p = np.asarray(positions, dtype=float).reshape(-1, 2)
        if len(p) < 2:
            return np.empty((0, 2), dtype=np.intp)
        from scipy.spatial import cKDTree  # lazy: see test_devices_rps_startup_imports

        pairs = cKDTree(p).query_pairs(self.delta, output_type="ndarray").astype(np.intp)
        return sorted_links(np.vstack((pairs, pairs[:, ::-1])))


@dataclass(frozen=True)
class KNearestTopology:
    """Each robot hears from its ``k`` nearest robots (directed: j → i when j is among i's k nearest)."""

    k: int

    def __post_init__(self) -> None:
        if isinstance(self.k, bool) or not isinstance(self.k, (int, np.integer)) or self.k < 1:
            raise ValueError(f"KNearestTopology: k must be an integer >= 1, got {self.k!r}")

    def links(self, positions: NDArray[np.float64]) -> Links:
        p = np.asarray(positions, dtype=float).reshape(-1, 2)
        n = len(p)
        k = min(int(self.k), n - 1)
        if k < 1:
            return np.empty((0, 2), dtype=np.intp)
        from scipy.spatial import cKDTree  # lazy: see test_devices_rps_startup_imports

        _, idx = cKDTree(p).query(p, k=k + 1)
        idx = np.asarray(idx, dtype=np.intp).reshape(n, k + 1)
        receiver = np.repeat(np.arange(n, dtype=np.intp), k + 1)
        sender = idx.ravel()
        keep = sender != receiver
        # a tie at distance 0 can put i's own index later than first: drop self, keep k others
        links = np.column_stack((sender[keep], receiver[keep]))
        counts = np.bincount(links[:, 1], minlength=n)
        if np.any(counts > k):  # no self-link was dropped for some robot: keep its k nearest others
            first = np.concatenate(([0], np.cumsum(counts)[:-1]))
            rank = np.arange(len(links)) - np.repeat(first, counts)
            links = links[rank < k]
        return sorted_links(links)
