"""rps.utilities.graph names over :mod:`swarmdeck.core.graphs` (inputs are never modified)."""
from __future__ import annotations

import numpy as np

from swarmdeck.core.graphs import (
    complete_laplacian,
    cycle_laplacian,
    line_laplacian,
    random_connected_laplacian,
    topological_neighbors,
)
from swarmdeck.core.graphs import (
    delta_disk_neighbors as _delta_disk_neighbors,
)


def cycle_GL(N: int) -> np.ndarray:
    """Laplacian of the cycle graph."""
    return cycle_laplacian(N)


def lineGL(N: int) -> np.ndarray:
    """Laplacian of the path graph."""
    return line_laplacian(N)


def completeGL(N: int) -> np.ndarray:
    """Laplacian of the complete graph."""
    return complete_laplacian(N)


def random_connectedGL(v: int, e: int) -> np.ndarray:
    """A random connected graph on v nodes with e extra edges."""
    return random_connected_laplacian(v, e)


def cycleGL(n: int) -> np.ndarray:
    """rps 2.0's name for :func:`cycle_GL`."""
    return cycle_laplacian(n)


def randomGL(v: int, e: int) -> np.ndarray:
    """A random graph on v nodes with e edges (rps: may be disconnected), as a Laplacian."""
    if not (isinstance(v, (int, np.integer)) and isinstance(e, (int, np.integer)) and v >= 1 and 0 <= e <= v * (v - 1) // 2):
        raise ValueError(f"randomGL needs 1 <= v and 0 <= e <= v(v-1)/2 edges, got v={v!r}, e={e!r}")
    rows, cols = np.triu_indices(int(v), 1)
    pick = np.random.choice(len(rows), size=int(e), replace=False)
    A = np.zeros((v, v))
    A[rows[pick], cols[pick]] = 1.0
    A = A + A.T
    return np.diag(A.sum(axis=1)) - A


def delta_disk_neighbors(poses, agent: int, delta: float) -> np.ndarray:
    """Agents within delta of ``agent``; poses (2 or 3, N) as in rps."""
    return _delta_disk_neighbors(np.asarray(poses, dtype=float).T, agent, delta)


__all__ = ["completeGL", "cycleGL", "cycle_GL", "delta_disk_neighbors", "lineGL", "randomGL", "random_connectedGL",
           "topological_neighbors"]
