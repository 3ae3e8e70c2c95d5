"""Robots already inside the unsafe set (h < 0) are separated, not stopped by an infeasible QP."""
from __future__ import annotations

import numpy as np
from scipy.spatial.distance import pdist

from swarmdeck.safety import BarrierConfig, SafetyFilter
from swarmdeck.safety.scenes import grid_scene


def test_overlapping_pair_separates() -> None:
    cfg = BarrierConfig()
    x = np.array([[0.0, 0.0], [0.1, 0.0]])
    f = SafetyFilter(cfg)
    u, diag = f.filter(x, np.array([[0.2, 0.0], [-0.2, 0.0]]))  # even while driving at each other
    assert diag.ok and diag.n_unsafe == 1 and "recovering" in diag.status and diag.n_clusters == 1
    assert u[1, 0] - u[0, 0] >= 0.95 * cfg.recovery_speed


def test_coincident_points_separate() -> None:
    x = np.array([[0.0, 0.0], [0.0, 0.0]])
    u, diag = SafetyFilter().filter(x, np.zeros((2, 2)))
    assert diag.ok
    assert np.linalg.norm(u[0] - u[1]) > 0.01


def test_glitch_in_a_crowd_returns_to_safe_set() -> None:
    """A tracking glitch drops one robot onto its neighbour; the loop restores h ≥ 0 and keeps the rest safe."""
    cfg = BarrierConfig()
    rng = np.random.default_rng(8)
    x, _ = grid_scene(25, rng, cfg)
    d = np.linalg.norm(x - x[0], axis=1)
    d[0] = np.inf
    k = int(np.argmin(d))
    x[k] = x[0] + 0.3 * (x[k] - x[0])
    f = SafetyFilter(cfg)
    for step in range(400):
        nominal = 0.2 * (x.mean(axis=0) - x)
        u, diag = f.filter(x, nominal)
        assert diag.ok, diag.status
        x = x + u * 0.033
        if diag.n_unsafe == 0:
            break
    assert diag.n_unsafe == 0
    for _ in range(100):
        u, diag = f.filter(x, 0.2 * (x.mean(axis=0) - x))
        x = x + u * 0.033
    assert pdist(x).min() >= cfg.safety_distance - 1e-3


def test_outside_wall_margin_moves_back() -> None:
    cfg = BarrierConfig()
    x = np.array([[1.58, 0.0]])  # beyond x_max − margin = 1.515
    u, diag = SafetyFilter(cfg).filter(x, np.array([[0.2, 0.0]]))
    assert diag.ok and u[0, 0] <= -0.95 * cfg.recovery_speed
