"""Diagnostics: consistent with the answer, JSON-able, cheap enough to always compute."""
from __future__ import annotations

import json

import numpy as np
from scipy.spatial.distance import pdist

from swarmdeck.safety import BarrierConfig, SafetyFilter
from swarmdeck.safety.scenes import grid_scene


def test_diagnostics_match_the_scene() -> None:
    cfg = BarrierConfig()
    rng = np.random.default_rng(3)
    x, nominal = grid_scene(30, rng, cfg)
    u, diag = SafetyFilter(cfg).filter(x, nominal)
    assert diag.ok and diag.status == "optimal"
    np.testing.assert_allclose(diag.min_distance, pdist(x).min(), rtol=1e-12)
    x_min, x_max, y_min, y_max = cfg.bounds
    clear = min((x[:, 0] - x_min).min(), (x_max - x[:, 0]).min(), (x[:, 1] - y_min).min(), (y_max - x[:, 1]).min())
    np.testing.assert_allclose(diag.min_wall_clearance, clear, rtol=1e-12)
    np.testing.assert_allclose(diag.intervention, np.linalg.norm(u - nominal, axis=1), atol=1e-15)
    assert diag.active_pairs.shape == (diag.active_h.shape[0], 2)
    assert diag.n_active >= diag.active_pairs.shape[0] > 0
    i, j = diag.active_pairs.T
    assert np.all(i < j)
    np.testing.assert_allclose(diag.active_h, np.sum((x[i] - x[j]) ** 2, axis=1) - cfg.safety_distance**2, rtol=1e-9)
    # active pair rows hold at equality: −2eᵀ(u_i − u_j) = γ h³
    e = x[i] - x[j]
    lhs = -2 * np.sum(e * (u[i] - u[j]), axis=1)
    np.testing.assert_allclose(lhs, cfg.gamma * diag.active_h**3, atol=1e-7)
    assert diag.n_constraints > 0 and diag.n_clusters == 0 and diag.solve_time_s > 0
    d = diag.to_dict()
    text = json.dumps(d, allow_nan=False)
    assert json.loads(text)["active_pairs"] == diag.active_pairs.tolist()


def test_to_dict_without_robots_is_json() -> None:
    u, diag = SafetyFilter().filter(np.zeros((0, 2)), np.zeros((0, 2)))
    assert u.shape == (0, 2) and diag.ok
    json.dumps(diag.to_dict(), allow_nan=False)
    u, diag = SafetyFilter().filter(np.zeros((1, 2)), np.zeros((1, 2)), obstacles=np.array([[1.0, 0.5]]))
    assert diag.ok and diag.min_distance == np.inf
    assert json.loads(json.dumps(diag.to_dict(), allow_nan=False))["min_distance"] is None
