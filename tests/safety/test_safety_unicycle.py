"""Unicycle filter: wheel limits, exact pass-through, the look-ahead maps, closed-loop safety."""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.distance import pdist

from swarmdeck.core.kinematics import lookahead_points, si_to_unicycle, unicycle_to_si, unicycle_to_wheels
from swarmdeck.safety import UnicycleParams, UnicycleSafetyFilter
from swarmdeck.safety.scenes import grid_scene


@settings(max_examples=40, deadline=None)
@given(n=st.integers(1, 30), seed=st.integers(0, 2**31 - 1), gain=st.floats(0.1, 4.0))
def test_wheel_limits_respected(n: int, seed: int, gain: float) -> None:
    rng = np.random.default_rng(seed)
    f = UnicycleSafetyFilter()
    x, _ = grid_scene(n, rng, f.config)
    poses = np.column_stack([x - 0.0, rng.uniform(-np.pi, np.pi, n)])
    v = rng.uniform(-0.2, 0.2, n) * gain
    w = rng.uniform(-4.0, 4.0, n) * gain
    vs, ws, diag = f.filter(poses, v, w)
    assert diag.ok, diag.status
    wr, wl = unicycle_to_wheels(vs, ws, f.params)
    assert np.all(np.abs(wr) <= f.params.max_wheel_speed + 1e-9)
    assert np.all(np.abs(wl) <= f.params.max_wheel_speed + 1e-9)


def test_safe_unicycle_command_returned_exactly() -> None:
    f = UnicycleSafetyFilter()
    poses = np.array([[-1.0, 0.0, 0.3], [1.0, 0.0, -2.0], [0.0, 0.5, 1.0]])
    v = np.array([0.1, -0.05, 0.0])
    w = np.array([0.5, 1.0, -2.0])
    vs, ws, diag = f.filter(poses, v, w)
    assert diag.nominal_was_safe
    assert np.array_equal(vs, v) and np.array_equal(ws, w)


def test_wheel_overspeed_is_projected() -> None:
    """A lone robot asked to spin beyond the wheel limit gets a command at the limit."""
    f = UnicycleSafetyFilter()
    vs, ws, diag = f.filter(np.array([[0.0, 0.0, 0.0]]), np.array([0.0]), np.array([10.0]))
    assert diag.ok and not diag.nominal_was_safe
    wr, wl = unicycle_to_wheels(vs, ws, f.params)
    np.testing.assert_allclose(max(abs(wr[0]), abs(wl[0])), f.params.max_wheel_speed, rtol=1e-6)


@given(x=st.floats(-1, 1), y=st.floats(-1, 1), th=st.floats(-4, 4), v=st.floats(-0.2, 0.2), w=st.floats(-3, 3))
@settings(max_examples=50, deadline=None)
def test_lookahead_maps_are_inverse(x: float, y: float, th: float, v: float, w: float) -> None:
    poses = np.array([[x, y, th]])
    u = unicycle_to_si(poses, np.array([v]), np.array([w]), 0.03)
    v2, w2 = si_to_unicycle(poses, u, 0.03)
    np.testing.assert_allclose([v2[0], w2[0]], [v, w], atol=1e-12)
    # finite difference: d/dt of the look-ahead point along the unicycle motion equals u
    h = 1e-6
    moved = np.array([[x + h * v * np.cos(th), y + h * v * np.sin(th), th + h * w]])
    fd = (lookahead_points(moved, 0.03) - lookahead_points(poses, 0.03)) / h
    np.testing.assert_allclose(fd, u, atol=1e-6)


def test_unicycle_closed_loop_stays_safe() -> None:
    """Random headings, every robot driving at the centroid at full wheel speed, exact unicycle steps."""
    rng = np.random.default_rng(7)
    params = UnicycleParams()
    f = UnicycleSafetyFilter(params=params)
    x, _ = grid_scene(15, rng, f.config, pitch=0.25)
    th = rng.uniform(-np.pi, np.pi, 15)
    poses = np.column_stack([x - params.lookahead * np.column_stack([np.cos(th), np.sin(th)]), th])
    dt = 0.033
    for _ in range(500):
        p = lookahead_points(poses, params.lookahead)
        u = (p.mean(axis=0) - p) * 2.0
        v, w = si_to_unicycle(poses, u, params.lookahead)
        vs, ws, diag = f.filter(poses, v, w)
        assert diag.ok, diag.status
        th = poses[:, 2]
        mid = th + 0.5 * ws * dt  # midpoint rule: exact to O(dt³), fine for a safety margin of 1e-3
        poses = np.column_stack([poses[:, 0] + vs * dt * np.cos(mid), poses[:, 1] + vs * dt * np.sin(mid), th + ws * dt])
        assert pdist(lookahead_points(poses, params.lookahead)).min() >= f.config.safety_distance - 1e-3
