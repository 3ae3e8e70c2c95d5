"""Paper Fig. 8: four robots swap positions across the arena, without collision or deadlock."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.distance import pdist

from swarmdeck.core.kinematics import lookahead_points
from swarmdeck.safety import BarrierConfig, SafetyFilter, UnicycleSafetyFilter

DT = 0.033
START = np.array([[-0.8, 0.0], [0.8, 0.0], [0.0, -0.7], [0.0, 0.7]])


def go_to(x: np.ndarray, goal: np.ndarray, vmax: float) -> np.ndarray:
    e = goal - x
    n = np.linalg.norm(e, axis=1, keepdims=True)
    return e * np.minimum(1.0, vmax / np.maximum(n, 1e-12))


@pytest.mark.parametrize("jitter", [0.0, 0.002])
def test_single_integrator_swap(jitter: float) -> None:
    cfg = BarrierConfig()
    x = START + np.random.default_rng(1).normal(0, jitter, START.shape)
    goal = -x
    f = SafetyFilter(cfg)
    closest = np.inf
    for _step in range(2500):
        u, diag = f.filter(x, go_to(x, goal, cfg.max_speed))
        assert diag.ok
        x = x + u * DT
        closest = min(closest, pdist(x).min())
        if np.linalg.norm(goal - x, axis=1).max() < 0.01:
            break
    assert np.linalg.norm(goal - x, axis=1).max() < 0.01, "deadlock: the swap did not finish"
    assert closest >= cfg.safety_distance - 1e-3


def test_unicycle_swap() -> None:
    """The same swap with unicycle robots (exact unicycle steps), filtered on the look-ahead points."""
    f = UnicycleSafetyFilter()
    ell = f.params.lookahead
    heading = np.arctan2(-START[:, 1], -START[:, 0])
    poses = np.column_stack([START, heading + 0.01])
    goal = -START
    closest = np.inf
    for _step in range(3000):
        p = lookahead_points(poses, ell)
        u = go_to(p, goal, 0.15)
        c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
        v_nom, w_nom = c * u[:, 0] + s * u[:, 1], (-s * u[:, 0] + c * u[:, 1]) / ell
        v, w, diag = f.filter(poses, v_nom, w_nom)
        assert diag.ok
        # exact unicycle step
        th = poses[:, 2]
        small = np.abs(w) < 1e-9
        wsafe = np.where(small, 1.0, w)
        dx = np.where(small, v * DT * np.cos(th), v / wsafe * (np.sin(th + w * DT) - np.sin(th)))
        dy = np.where(small, v * DT * np.sin(th), -v / wsafe * (np.cos(th + w * DT) - np.cos(th)))
        poses = np.column_stack([poses[:, 0] + dx, poses[:, 1] + dy, th + w * DT])
        closest = min(closest, pdist(lookahead_points(poses, ell)).min())
        if np.linalg.norm(goal - lookahead_points(poses, ell), axis=1).max() < 0.02:
            break
    assert np.linalg.norm(goal - lookahead_points(poses, ell), axis=1).max() < 0.02, "deadlock"
    assert closest >= f.config.safety_distance - 1e-3
    assert pdist(poses[:, :2]).min() >= 0.11 - 1e-3  # bodies (Ø 0.11 m) never touch
