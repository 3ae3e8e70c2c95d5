"""Line-segment obstacles in the barrier (safety/constraints.py segment_rows): the row in closed form, the
closed loop keeps every robot off every segment and every pair apart in every mode, and no obstacles builds
exactly the rows it always did."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from swarmdeck.core.obstacles import Obstacles, point_segment_distance
from swarmdeck.safety import BarrierConfig, SafetyFilter, UnicycleSafetyFilter
from swarmdeck.safety.constraints import SEGMENT, barrier_rows, segment_rows
from swarmdeck.safety.filter import _KIND_NAMES

WALL = Obstacles([[[-0.5, 0.0], [0.5, 0.0]]])


def test_segment_row_in_closed_form() -> None:
    cfg = BarrierConfig(obstacles=WALL)
    pts = np.array([[0.1, 0.15], [0.6, -0.1], [1.4, 0.9]])
    rows = segment_rows(pts, cfg)
    assert rows.i.tolist() == [0, 1] and np.all(rows.kind == SEGMENT) and np.all(rows.j == -1)
    d = np.array([0.15, np.hypot(0.1, 0.1)])
    np.testing.assert_allclose(rows.h, d - cfg.margin, rtol=1e-14)
    np.testing.assert_allclose(rows.ci, [[0.0, -1.0], [-np.sqrt(0.5), np.sqrt(0.5)]], atol=1e-14)
    np.testing.assert_allclose(rows.b, cfg.wall_gain * cfg.gamma * (d - cfg.margin) ** 3, rtol=1e-14)
    assert _KIND_NAMES[SEGMENT] == "segment"


def test_no_obstacles_builds_the_same_rows() -> None:
    rng = np.random.default_rng(3)
    pts = rng.uniform(-1.4, 1.4, (40, 2)) * [1, 0.6]
    a = barrier_rows(pts, BarrierConfig())
    b = barrier_rows(pts, BarrierConfig(obstacles=Obstacles.none()))
    for f in ("i", "j", "ci", "cj", "b", "h", "kind", "key"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))
    assert BarrierConfig(obstacles=Obstacles.none()) == BarrierConfig()


def test_keys_are_unique_beside_limit_and_point_rows() -> None:
    cfg = BarrierConfig(obstacles=Obstacles.from_polygons([[[-0.2, -0.2], [0.2, -0.2], [0.2, 0.2], [-0.2, 0.2]]]))
    pts = np.array([[0.0, 0.35], [0.35, 0.0], [-0.3, -0.3]])
    poses = np.column_stack([pts, np.zeros(3)])
    filt = UnicycleSafetyFilter(cfg)
    _, _, diag = filt.filter(poses, np.full(3, 0.1), np.zeros(3), obstacles=np.array([[0.0, 0.6]]))
    assert diag.ok, diag.status
    rows = barrier_rows(pts, cfg, np.array([[0.0, 0.6]]))
    assert np.unique(rows.key).size == rows.m


def test_config_round_trips_obstacles() -> None:
    cfg = BarrierConfig(obstacles=WALL)
    assert BarrierConfig.from_dict(cfg.to_dict()) == cfg
    assert "obstacles" not in BarrierConfig().to_dict()
    with pytest.raises(ValueError, match="BarrierConfig: obstacles: segment 0 has zero length"):
        BarrierConfig(obstacles=[[[0, 0], [0, 0]]])


def _start(rng: np.random.Generator, seg: np.ndarray, n: int, margin: float, ds: float) -> np.ndarray | None:
    pts: list[np.ndarray] = []
    for _ in range(400):
        p = rng.uniform([-1.4, -0.8], [1.4, 0.8])
        if point_segment_distance(p[None], seg).min() < margin + 0.02:
            continue
        if pts and np.min(np.linalg.norm(np.array(pts) - p, axis=1)) < ds + 0.02:
            continue
        pts.append(p)
        if len(pts) == n:
            return np.array(pts)
    return None


@settings(max_examples=12, suppress_health_check=[HealthCheck.too_slow], deadline=None)
@given(seed=st.integers(0, 2**31 - 1), n=st.integers(2, 8),
       mode=st.sampled_from(["centralised", "anytime", "distributed"]))
def test_closed_loop_keeps_robots_off_segments_and_apart(seed: int, n: int, mode: str) -> None:
    rng = np.random.default_rng(seed)
    segs = rng.uniform([-1.2, -0.7], [1.2, 0.7], (3, 2, 2))
    segs = segs[np.linalg.norm(segs[:, 1] - segs[:, 0], axis=1) > 0.05]
    box = [[0.3, 0.1], [0.7, 0.1], [0.7, 0.4]]  # a triangle as a polygon
    obs = Obstacles.from_polygons([box], segments=segs)
    cfg = BarrierConfig(obstacles=obs, mode=mode, work_budget=40 if mode == "anytime" else None)  # type: ignore[arg-type]
    x = _start(rng, obs.segments, n, cfg.margin, cfg.safety_distance)
    if x is None:
        return
    goals = rng.uniform([-1.4, -0.8], [1.4, 0.8], (n, 2))
    filt = SafetyFilter(cfg)
    for _ in range(100):
        nominal = goals - x
        speed = np.linalg.norm(nominal, axis=1, keepdims=True)
        nominal = nominal * np.minimum(1.0, cfg.max_speed / np.maximum(speed, 1e-12))
        u, diag = filt.filter(x, nominal)
        assert diag.ok, diag.status
        x = x + u * cfg.dt
        d_seg = point_segment_distance(x, obs.segments).min()
        assert d_seg >= cfg.margin - 1e-9, (d_seg, cfg.margin)
        e = x[:, None] - x[None]
        d = np.sqrt((e**2).sum(-1)) + np.eye(n) * 9
        assert d.min() >= cfg.safety_distance - 1e-9


def test_a_robot_driven_at_a_wall_stops_in_front_of_it() -> None:
    cfg = BarrierConfig(obstacles=WALL)
    filt = UnicycleSafetyFilter(cfg)
    pose = np.array([[0.0, 0.4, -np.pi / 2]])
    for _ in range(300):
        v, w, diag = filt.filter(pose, np.array([0.2]), np.array([0.0]))
        assert diag.ok
        pose = pose + cfg.dt * np.column_stack([v * np.cos(pose[:, 2]), v * np.sin(pose[:, 2]), w])
    point = pose[:, :2] + 0.03 * np.column_stack([np.cos(pose[:, 2]), np.sin(pose[:, 2])])
    d = point_segment_distance(point, WALL.segments)[0, 0]
    assert cfg.margin - 1e-9 <= d < cfg.margin + 0.05  # it got close (the cubic κ slows the approach), never closer


def test_replace_keeps_obstacles() -> None:
    cfg = dataclasses.replace(BarrierConfig(obstacles=WALL), pairs=False)
    assert cfg.obstacles == WALL
