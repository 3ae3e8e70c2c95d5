"""Robots already inside the unsafe set (h < 0) are separated, not stopped by an infeasible QP.

A row with h < 0 keeps its plain barrier bound (the cubic κ demands separation); deep overlaps
(closer than D_s − recovery_depth) demand recovery_speed, so they end within a bounded time.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.distance import pdist

from swarmdeck.safety import BarrierConfig, SafetyFilter
from swarmdeck.safety.scenes import grid_scene


def plain_demand(cfg: BarrierConfig, d: float) -> float:
    """Separation speed (m/s, relative) the plain pair row demands at distance d < D_s."""
    return -cfg.gamma * cfg.kappa(d * d - cfg.safety_distance**2) / (2 * d)


def test_shallow_overlap_keeps_the_plain_row() -> None:
    cfg = BarrierConfig()
    x = np.array([[0.0, 0.0], [0.15, 0.0]])  # h < 0, not deep (0.15 > D_s − recovery_depth = 0.14)
    u, diag = SafetyFilter(cfg).filter(x, np.array([[0.2, 0.0], [-0.2, 0.0]]))  # driving at each other
    assert diag.ok and diag.n_unsafe == 1 and "recovering" in diag.status and diag.n_clusters == 1
    np.testing.assert_allclose(u[1, 0] - u[0, 0], plain_demand(cfg, 0.15), rtol=0, atol=1e-10)


def test_deep_overlap_separates_at_recovery_speed() -> None:
    cfg = BarrierConfig()
    x = np.array([[0.0, 0.0], [0.1, 0.0]])
    u, diag = SafetyFilter(cfg).filter(x, np.array([[0.2, 0.0], [-0.2, 0.0]]))
    assert diag.ok and diag.n_unsafe == 1
    # rows are normalised: n·(u_j − u_i) ≥ recovery_speed along the pair
    assert u[1, 0] - u[0, 0] == pytest.approx(cfg.recovery_speed, rel=1e-9)


def test_coincident_points_separate() -> None:
    x = np.array([[0.0, 0.0], [0.0, 0.0]])
    u, diag = SafetyFilter().filter(x, np.zeros((2, 2)))
    assert diag.ok
    assert np.linalg.norm(u[0] - u[1]) > 0.01


def freezing_cluster(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """3–8 robots heaped within a few cm (a mis-placed start or a tracking glitch)."""
    rng = np.random.default_rng(seed)
    k = rng.integers(3, 9)
    c = rng.uniform([-1.2, -0.7], [1.2, 0.7])
    x = c + rng.normal(0, rng.choice([0.005, 0.02, 0.05]), (k, 2))
    return x, rng.normal(0, 0.1, (k, 2))


@pytest.mark.parametrize("seed", [26, 118, 177])
def test_heaped_clusters_separate_in_bounded_ticks(seed: int) -> None:
    """These clusters fail-stopped with 'not converged to tolerance (almost solved)' on every tick
    (the swarm froze). Now every tick is answered and, even with nominals driving the robots
    towards each other, every pair is beyond D_s − recovery_depth within 100 ticks (3.3 s)."""
    cfg = BarrierConfig()
    x, nominal = freezing_cluster(seed)
    f = SafetyFilter(cfg)
    for tick in range(100):
        if tick % 2:  # alternate a fixed random nominal and 'everyone to the centroid'
            c = x.mean(axis=0) - x
            nominal = 0.2 * c / np.maximum(np.linalg.norm(c, axis=1, keepdims=True), 1e-9)
        u, diag = f.filter(x, nominal)
        assert diag.ok, diag.status
        assert np.all(np.einsum("kd,kd->k", u, u) <= cfg.max_speed**2)
        before = pdist(x)
        x = x + u * cfg.dt
        deep = before < cfg.safety_distance - cfg.recovery_depth
        assert np.all(pdist(x)[deep] > before[deep])  # every deep pair moves apart on every tick
        if pdist(x).min() >= cfg.safety_distance - cfg.recovery_depth:
            break
    assert pdist(x).min() >= cfg.safety_distance - cfg.recovery_depth


def test_infeasible_recovery_rows_fall_back_to_soft_separation() -> None:
    """Three robots in a corridor too narrow for them: the recovery rows are infeasible, the soft
    form ("no further approach" + targets) answers and the robots are not stopped."""
    x = np.array([[-0.14, 0.0], [0.0, 0.0], [0.14, 0.0]])
    cfg = BarrierConfig(bounds=(-0.2, 0.2, -1.0, 1.0))
    u, diag = SafetyFilter(cfg).filter(x, np.array([[0.1, 0.0], [0.0, 0.1], [-0.1, 0.0]]))
    assert diag.ok and "soft separation" in diag.status, diag.status
    assert u[0, 0] <= 1e-7 and u[2, 0] >= -1e-7  # no further approach to the walls or each other
    assert u[1, 0] - u[0, 0] >= -1e-7 and u[2, 0] - u[1, 0] >= -1e-7


def test_glitch_in_a_crowd_recovers_without_disturbing_the_rest() -> None:
    """A tracking glitch drops one robot onto its neighbour while everyone drives to the centroid:
    the pair leaves the deep overlap within a bounded time and no other pair becomes unsafe."""
    cfg = BarrierConfig()
    rng = np.random.default_rng(8)
    x, _ = grid_scene(25, rng, cfg)
    d = np.linalg.norm(x - x[0], axis=1)
    d[0] = np.inf
    k = int(np.argmin(d))
    x[k] = x[0] + 0.3 * (x[k] - x[0])
    others = np.ones(25, dtype=bool)
    others[[0, k]] = False
    f = SafetyFilter(cfg)
    for _ in range(120):
        u, diag = f.filter(x, 0.2 * (x.mean(axis=0) - x))
        assert diag.ok, diag.status
        x = x + u * 0.033
        assert pdist(x[others]).min() >= cfg.safety_distance - 1e-3
    assert np.linalg.norm(x[k] - x[0]) >= cfg.safety_distance - cfg.recovery_depth


def test_outside_wall_margin_moves_back() -> None:
    cfg = BarrierConfig()
    x = np.array([[1.58, 0.0]])  # beyond x_max − margin = 1.515 by more than recovery_depth
    u, diag = SafetyFilter(cfg).filter(x, np.array([[0.2, 0.0]]))
    assert diag.ok and u[0, 0] == pytest.approx(-cfg.recovery_speed, rel=1e-9)
