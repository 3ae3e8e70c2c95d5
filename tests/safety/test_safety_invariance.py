"""Invariance: from safe starts, under adversarial nominals, the closed loop x ← x + u·dt stays safe.

Every pairwise distance stays ≥ D_s − 1e-3 and every point inside the arena
(indeed inside the wall margin, to 1e-3), for N = 2 … 50 and > 10 000 steps in total.
"""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.distance import pdist

from swarmdeck.safety import BarrierConfig, SafetyFilter
from swarmdeck.safety.scenes import grid_scene

DT = 0.033
MODES = ("converge", "chase", "walls", "random", "swirl")


def adversarial(mode: str, x: np.ndarray, rng: np.random.Generator, target: np.ndarray, vmax: float) -> np.ndarray:
    """Nominal commands that push robots into each other or the walls, saturated at 1.5·v_max."""
    if mode == "converge":  # everyone drives at the centroid
        u = x.mean(axis=0) - x
    elif mode == "chase":  # everyone drives at another robot
        u = x[target] - x
    elif mode == "walls":  # straight out of the arena
        u = x + rng.normal(0, 0.05, x.shape)
    elif mode == "swirl":
        c = x - x.mean(axis=0)
        u = np.stack([-c[:, 1], c[:, 0]], axis=1) - 0.5 * c
    else:
        u = rng.normal(0, 1, x.shape)
    n = np.linalg.norm(u, axis=1, keepdims=True)
    return u / np.maximum(n, 1e-12) * 1.5 * vmax


def assert_safe(x: np.ndarray, cfg: BarrierConfig) -> None:
    if x.shape[0] >= 2:
        assert pdist(x).min() >= cfg.safety_distance - 1e-3
    x_min, x_max, y_min, y_max = cfg.bounds
    m = cfg.margin - 1e-3
    assert np.all(x[:, 0] >= x_min + m) and np.all(x[:, 0] <= x_max - m)
    assert np.all(x[:, 1] >= y_min + m) and np.all(x[:, 1] <= y_max - m)


def run(cfg: BarrierConfig, n: int, steps: int, seed: int) -> int:
    rng = np.random.default_rng(seed)
    x, _ = grid_scene(n, rng, cfg)
    f = SafetyFilter(cfg)
    target = rng.permutation(n)
    mode = MODES[seed % len(MODES)]
    for k in range(steps):
        if k % 60 == 0:
            mode = MODES[rng.integers(len(MODES))]
            target = rng.permutation(n)
        nominal = adversarial(mode, x, rng, target, cfg.max_speed)
        u, diag = f.filter(x, nominal)
        assert diag.ok, diag.status
        assert np.all(np.linalg.norm(u, axis=1) <= cfg.max_speed + 1e-9)
        x = x + u * DT
        assert_safe(x, cfg)
    return steps


@settings(max_examples=25, deadline=None)
@given(n=st.integers(2, 50), seed=st.integers(0, 2**31 - 1))
def test_invariance_hypothesis(n: int, seed: int) -> None:
    run(BarrierConfig(), n, 150, seed)


def test_invariance_long_runs() -> None:
    """Long deterministic runs; with the hypothesis examples > 10 000 steps in total."""
    total = 0
    for n, steps in ((2, 2000), (3, 1000), (5, 1000), (12, 800), (25, 500), (50, 300)):
        total += run(BarrierConfig(), n, steps, seed=n)
    assert total >= 5600  # + 25 × 150 hypothesis steps + 2 × 700 below > 10 000


def test_invariance_linear_class_k() -> None:
    """The paper's linear κ(h) = h, with γ·dt < 1 so the discrete-time loop stays safe."""
    cfg = BarrierConfig(class_k="linear", gamma=20.0)
    run(cfg, 20, 700, seed=3)


def test_invariance_small_arena_dense() -> None:
    """A crowded small arena: 30 robots in 1.6 × 1.2 m."""
    cfg = BarrierConfig(bounds=(-0.8, 0.8, -0.6, 0.6))
    run(cfg, 30, 700, seed=11)
