"""Per-robot wall rows: each robot held inside its own rectangle (its region of a shared floor), vectorised."""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.safety.config import BarrierConfig
from swarmdeck.safety.constraints import WALL, barrier_rows, wall_rows
from swarmdeck.safety.filter import SafetyFilter
from swarmdeck.safety.unicycle import UnicycleSafetyFilter


def test_the_floor_for_every_robot_gives_the_rows_of_the_plain_walls_bit_for_bit():
    cfg = BarrierConfig()
    rng = np.random.default_rng(3)
    points = rng.uniform([-1.6, -1.0], [1.6, 1.0], (40, 2))
    plain = wall_rows(points, cfg)
    tiled = wall_rows(points, cfg, np.tile(np.asarray(cfg.bounds, dtype=float), (40, 1)))
    for f in ("i", "j", "ci", "cj", "b", "h", "kind", "key"):
        assert np.array_equal(getattr(plain, f), getattr(tiled, f)), f


def test_a_robot_near_its_region_edge_gets_a_wall_row_there_not_at_the_floor():
    cfg = BarrierConfig()
    points = np.array([[-0.05, 0.0], [0.05, 0.0]])  # the two sides of a region edge at x = 0
    rects = np.array([[-1.6, 0.0, -1.0, 1.0], [0.0, 1.6, -1.0, 1.0]])
    rows = barrier_rows(points, cfg, robot_bounds=rects)
    walls = rows.select(rows.kind == WALL)
    assert sorted(zip(walls.i.tolist(), walls.ci[:, 0].tolist())) == [(0, 1.0), (1, -1.0)]
    assert np.all(walls.h < 0)  # both inside the margin D_s/2 of the shared edge


@settings(max_examples=25)
@given(st.integers(0, 2**31 - 1), st.integers(2, 12), st.floats(0.3, 3.0))
def test_full_speed_at_the_walls_never_leaves_the_rectangles(seed, n, push):
    """Each robot in its own random rectangle driving at its walls at up to ``push`` × v_max: one closed loop
    of 60 periods keeps every point inside its rectangle less the wall margin (the rows' discrete guarantee)."""
    cfg = BarrierConfig()
    rng = np.random.default_rng(seed)
    lo = rng.uniform([-1.6, -1.0], [1.0, 0.4], (n, 2))
    size = rng.uniform(0.3, 0.6, (n, 2))
    rects = np.column_stack([lo[:, 0], lo[:, 0] + size[:, 0], lo[:, 1], lo[:, 1] + size[:, 1]])
    m = cfg.margin
    points = rng.uniform(rects[:, [0, 2]] + m, rects[:, [1, 3]] - m)
    filt = SafetyFilter(BarrierConfig(pairs=False))  # overlapping rectangles: only the walls are under test
    direction = rng.normal(size=(n, 2))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    for _ in range(60):
        u, diag = filt.filter(points, push * cfg.max_speed * direction, robot_bounds=rects)
        assert diag.ok, diag.status
        points = points + u * cfg.dt
        assert np.all(points[:, 0] >= rects[:, 0] + m - 1e-6) and np.all(points[:, 0] <= rects[:, 1] - m + 1e-6)
        assert np.all(points[:, 1] >= rects[:, 2] + m - 1e-6) and np.all(points[:, 1] <= rects[:, 3] - m + 1e-6)


def test_bad_per_robot_bounds_stop_every_robot_naming_them():
    filt = SafetyFilter()
    u, diag = filt.filter(np.zeros((2, 2)), np.ones((2, 2)), robot_bounds=np.zeros((3, 4)))
    assert not diag.ok and "robot_bounds must have shape (2, 4)" in diag.status and not u.any()
    u, diag = filt.filter(np.zeros((2, 2)), np.ones((2, 2)), robot_bounds=[[0, 1, 0, 1], [1, 0, 0, 1]])
    assert not diag.ok and "robot_bounds rows [1]" in diag.status
    v, w, diag = UnicycleSafetyFilter().filter(np.zeros((1, 3)), [0.1], [0.0], robot_bounds=[[0, 1, 0, np.nan]])
    assert not diag.ok and "robot_bounds" in diag.status and v[0] == 0.0
