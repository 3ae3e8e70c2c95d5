"""rps.utilities.graph names over :mod:`swarmdeck.core.graphs` (inputs are never modified)."""
from __future__ import annotations

import numpy as np

from swarmdeck.core.graphs import (
    complete_laplacian,
    cycle_laplacian,
    delta_disk_neighbors as _delta_disk_neighbors,
    line_laplacian,
    random_connected_laplacian,
    topological_neighbors,
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


def delta_disk_neighbors(poses, agent: int, delta: float) -> np.ndarray:
    """Agents within delta of ``agent``; poses (2 or 3, N) as in rps."""
    return _delta_disk_neighbors(np.asarray(poses, dtype=float).T, agent, delta)


__all__ = ["completeGL", "cycle_GL", "delta_disk_neighbors", "lineGL", "random_connectedGL", "topological_neighbors"]
