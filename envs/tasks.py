"""Rewards of the learning tasks (pure functions on numpy arrays; one reward per robot).

* ``coverage`` — r_i = −H_i / M with H_i = ∫_{V_i} ‖q − p_i‖² φ(q) dq the robot's share of the
  locational cost H = Σ_i H_i (REFERENCE.md §5; bounded Voronoi cells, ``swarmdeck.coverage``) and
  M = ∫φ over the arena, so Σ_i r_i = −H/M (m²), the normalised cost the coverage laws descend.
* ``formation`` — r_i = −‖p_i − g_i‖ (m): robot i's distance to its slot g_i of a regular polygon
  (radius ``formation_radius``) centred in the arena.
* ``rendezvous`` — r_i = −‖p_i − p̄‖ (m): the distance to the swarm's mean position.

``p`` are the look-ahead points (N, 2), the points the actions move.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.bounds import Bounds

TASKS = ("coverage", "formation", "rendezvous")

FloatArray = NDArray[np.float64]


def formation_slots(n: int, radius: float, centre: tuple[float, float] = (0.0, 0.0)) -> FloatArray:
    """(n, 2) slots of a regular n-gon of circumradius ``radius`` (m), slot 0 on +x, counter-clockwise."""
    ang = 2.0 * np.pi * np.arange(n) / max(n, 1)
    return np.column_stack((centre[0] + radius * np.cos(ang), centre[1] + radius * np.sin(ang)))


def rendezvous_reward(points: FloatArray) -> FloatArray:
    """(N,) −‖p_i − p̄‖ (m)."""
    return -np.linalg.norm(points - points.mean(axis=0), axis=1)


def formation_reward(points: FloatArray, slots: FloatArray) -> FloatArray:
    """(N,) −‖p_i − g_i‖ (m)."""
    return -np.linalg.norm(points - slots, axis=1)


def coverage_cells(points: FloatArray, density: Any, bounds: Bounds,
                   wall_margin: float = 0.02, min_separation: float = 1e-3) -> Any:
    """Cell moments (``swarmdeck.coverage.CellMoments``: masses, centroids, cost H_i per robot) of ``points``
    under ``density`` (a ``GaussianMixture``), with the coverage package's pre-conditioning."""
    from swarmdeck.coverage import bounded_voronoi, cell_moments, precondition_positions

    pts, _ = precondition_positions(points, bounds, wall_margin, min_separation)
    return cell_moments(bounded_voronoi(pts, bounds), density)


def coverage_reward(moments: Any) -> FloatArray:
    """(N,) −H_i / ∫φ (m²) from :func:`coverage_cells`."""
    total = float(np.sum(moments.masses))
    return -np.asarray(moments.cost, dtype=float) / (total if total > 0 else 1.0)
