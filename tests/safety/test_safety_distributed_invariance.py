"""Distributed barrier, closed loop: no pair row violated, no collision, for N up to 200.

Random configurations (γ, D_s, κ, v_max, arena sized for N) and adversarial
nominals (everyone at the centroid, chasing another robot, out through the
walls, swirling, random), x ← x + u·dt. Every tick: the filter succeeds, every
*centralised* row (pair, wall) holds for the commands the robots chose on their
own halves, speeds stay bounded; every distance stays ≥ D_s (the discrete step
keeps h ≥ 0 exactly when γ·dt·h² ≤ 1 for the cubic κ, γ·dt ≤ 1 for the linear
one, which the strategies respect) and every point inside the wall margin.
"""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.distance import pdist
from test_safety_invariance import DT, MODES, adversarial  # the same adversarial nominals as the centralised test

from swarmdeck.core.kinematics import lookahead_points, si_to_unicycle
from swarmdeck.safety import BarrierConfig, SafetyFilter, UnicycleParams, UnicycleSafetyFilter
from swarmdeck.safety.constraints import barrier_rows
from swarmdeck.safety.scenes import arena_for, grid_scene

configs = st.builds(
    lambda cubic, gamma, ds, vmax: BarrierConfig(
        class_k="cubic" if cubic else "linear", gamma=gamma if cubic else min(gamma, 1 / DT),
        safety_distance=ds, max_speed=vmax, dt=DT, mode="distributed"),
    st.booleans(), st.floats(10.0, 200.0), st.floats(0.12, 0.2), st.floats(0.05, 0.3))


@settings(max_examples=12, deadline=None)
@given(cfg=configs, n=st.integers(2, 200), seed=st.integers(0, 2**32 - 1))
def test_closed_loop_keeps_every_pair_row(cfg: BarrierConfig, n: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    pitch = cfg.safety_distance + 0.02
    cfg = BarrierConfig(**{**cfg.to_dict(), "bounds": arena_for(n, pitch, fill=0.7, margin=cfg.margin + 0.01)})
    x, _ = grid_scene(n, rng, cfg, pitch=pitch)
    f = SafetyFilter(cfg)
    steps = 40 if n > 60 else 120
    target = rng.permutation(n)
    mode = MODES[seed % len(MODES)]
    for k in range(steps):
        if k % 30 == 0:
            mode, target = MODES[rng.integers(len(MODES))], rng.permutation(n)
        u, diag = f.filter(x, adversarial(mode, x, rng, target, cfg.max_speed))
        assert diag.ok and diag.method in ("distributed",), diag.status
        rows = barrier_rows(x, cfg)
        assert np.all(rows.lhs(u) <= rows.b + 1e-9), "a centralised row is violated by the halves' answers"
        assert np.all(np.linalg.norm(u, axis=1) <= cfg.max_speed * (1 + 1e-9))
        x = x + u * DT
        if n >= 2:
            assert pdist(x).min() >= cfg.safety_distance - 1e-7
        x_min, x_max, y_min, y_max = cfg.bounds
        m = cfg.margin - 1e-7
        assert np.all((x[:, 0] >= x_min + m) & (x[:, 0] <= x_max - m))
        assert np.all((x[:, 1] >= y_min + m) & (x[:, 1] <= y_max - m))


def test_unicycle_distributed_closed_loop() -> None:
    """The unicycle form: wheel-limit rows instead of the disc, every wheel within its limit, no collision."""
    rng = np.random.default_rng(3)
    params = UnicycleParams()
    f = UnicycleSafetyFilter(BarrierConfig(mode="distributed"), params)
    n = 30
    x, _ = grid_scene(n, rng, f.config, pitch=0.22)
    th = rng.uniform(-np.pi, np.pi, n)
    poses = np.column_stack([x - params.lookahead * np.column_stack([np.cos(th), np.sin(th)]), th])
    for _ in range(300):
        p = lookahead_points(poses, params.lookahead)
        v, w = si_to_unicycle(poses, (p.mean(axis=0) - p) * 2.0, params.lookahead)
        vs, ws, diag = f.filter(poses, v, w)
        assert diag.ok and diag.method == "distributed", diag.status
        wr = (2 * vs + params.axle_length * ws) / (2 * params.wheel_radius)
        wl = (2 * vs - params.axle_length * ws) / (2 * params.wheel_radius)
        assert np.all(np.maximum(np.abs(wr), np.abs(wl)) <= params.max_wheel_speed * (1 + 1e-12))
        th = poses[:, 2]
        mid = th + 0.5 * ws * DT  # midpoint rule: exact to O(dt³)
        poses = np.column_stack([poses[:, 0] + vs * DT * np.cos(mid), poses[:, 1] + vs * DT * np.sin(mid),
                                 th + ws * DT])
        assert pdist(lookahead_points(poses, params.lookahead)).min() >= f.config.safety_distance - 1e-3


def test_robots_inside_the_unsafe_set_separate_or_hold() -> None:
    """Two robots closer than D_s: each takes half of the separation; a squeezed robot holds still."""
    cfg = BarrierConfig(mode="distributed")
    x = np.array([[0.0, 0.0], [0.15, 0.0], [0.6, 0.0]])
    u, diag = SafetyFilter(cfg).filter(x, np.array([[0.1, 0.0], [-0.1, 0.0], [0.0, 0.0]]))
    assert diag.ok and diag.n_unsafe == 1
    assert u[0, 0] <= -cfg.recovery_speed / 2 + 1e-12 and u[1, 0] >= cfg.recovery_speed / 2 - 1e-12
