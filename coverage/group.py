"""Small group behaviours as plain controllers on arrays (paper §V-A, §V-B).

Each returns single-integrator velocities ``(N, 2)`` for positions ``(N, 2)``.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def consensus(positions: ArrayLike, laplacian: ArrayLike, gain: float = 1.0) -> FloatArray:
    """Rendezvous/consensus ẋ_i = gain · Σ_{j∈N_i} (x_j − x_i) = −gain · (L x)_i (paper §V-A).

    For a connected undirected graph the centroid is invariant and every agent
    converges to it.
    """
    x = np.asarray(positions, dtype=float)
    L = np.asarray(laplacian, dtype=float)
    if L.shape != (len(x), len(x)):
        raise ValueError(f"laplacian must have shape ({len(x)}, {len(x)}), got {L.shape}")
    return -gain * (L @ x)


def formation_energy(positions: ArrayLike, edges: ArrayLike, distances: ArrayLike, alpha: float = 1.0) -> float:
    """Edge-tension energy E = Σ_{(i,j)} α/4 (‖x_i − x_j‖² − d_ij²)² (paper §V-B)."""
    x = np.asarray(positions, dtype=float)
    e = np.asarray(edges, dtype=np.intp)
    d = np.asarray(distances, dtype=float)
    sq = np.sum((x[e[:, 0]] - x[e[:, 1]]) ** 2, axis=1)
    return float(np.sum(alpha / 4.0 * (sq - d**2) ** 2))


def formation_control(positions: ArrayLike, edges: ArrayLike, distances: ArrayLike, alpha: float = 1.0) -> FloatArray:
    """Gradient descent on the edge-tension energy (paper §V-B):

    ẋ_i = −∂E/∂x_i = α Σ_{j∈N_i} (‖x_i − x_j‖² − d_ij²)(x_j − x_i).

    Args:
        positions: ``(N, 2)``, m.
        edges: ``(E, 2)`` node pairs of a rigid graph.
        distances: ``(E,)`` desired lengths d_ij, m.
        alpha: gain, 1/(m² s).
    """
    x = np.asarray(positions, dtype=float)
    e = np.asarray(edges, dtype=np.intp)
    d = np.asarray(distances, dtype=float)
    if e.ndim != 2 or e.shape[1] != 2 or d.shape != (len(e),):
        raise ValueError(f"edges must be (E, 2) and distances (E,), got {e.shape} and {d.shape}")
    diff = x[e[:, 1]] - x[e[:, 0]]  # x_j - x_i
    tension = alpha * (np.sum(diff**2, axis=1) - d**2)
    force = tension[:, None] * diff
    u = np.zeros_like(x)
    np.add.at(u, e[:, 0], force)
    np.add.at(u, e[:, 1], -force)
    return u


def formation_errors(positions: ArrayLike, edges: ArrayLike, distances: ArrayLike) -> FloatArray:
    """``(E,)`` absolute edge-length errors |‖x_i − x_j‖ − d_ij|, m."""
    x = np.asarray(positions, dtype=float)
    e = np.asarray(edges, dtype=np.intp)
    return np.abs(np.linalg.norm(x[e[:, 0]] - x[e[:, 1]], axis=1) - np.asarray(distances, dtype=float))
