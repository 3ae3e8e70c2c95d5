"""The barrier's cheaper small-N forms give the bits of the general forms they stand in for (issue 28, qp7).

At rps sizes (N <= 12) a barrier call is mostly per-call overhead, so some steps take a shorter way: wall rows
with one rectangle use scalar bounds (the per-robot path broadcasts arrays of the same numbers) and skip the row
arrays when no robot is near a wall; the dense pair search's rows are in key order already (the k-d tree's are
sorted); the diagnostics' wall clearance is min/max of the coordinates minus the bounds; wheel-limit rows are
written into one array; ``Rows.concat`` of one non-empty part returns it; the active set's certificate reads the
working rows' residuals from the slack of all rows. Each is checked here against the general form, boundary
cases included (robots exactly at the wall-row radius, pairs exactly at the neighbour radius, coincident robots,
headings on the axes).
"""
from __future__ import annotations

import dataclasses

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from swarmdeck.core.kinematics import UnicycleParams
from swarmdeck.safety import BarrierConfig, SafetyFilter
from swarmdeck.safety.active_set import _Working
from swarmdeck.safety.constraints import _FIELDS, Rows, pair_rows, wall_rows
from swarmdeck.safety.small_kernels import SMALL_ROBOTS
from swarmdeck.safety.unicycle import wheel_limit_rows


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def _same_rows(a: Rows, b: Rows) -> bool:
    return all(_same(getattr(a, f), getattr(b, f)) for f in _FIELDS)


def _points(seed: int, n: int, cfg: BarrierConfig, spread: float) -> np.ndarray:
    """Random points inside the arena, some exactly at the wall-row radius and some pairs exactly at the
    neighbour radius or on top of each other."""
    rng = np.random.default_rng(seed)
    x_min, x_max, y_min, y_max = cfg.bounds
    p = np.column_stack([rng.uniform(x_min, x_max, n), rng.uniform(y_min, y_max, n)]) * spread
    edge = cfg.wall_radius()
    for k in range(n):
        pick = rng.integers(0, 8)
        if pick == 0:
            p[k, 0] = x_max - edge  # clearance exactly at the radius (up to the subtraction's rounding)
        elif pick == 1:
            p[k, 1] = y_min + edge
        elif pick == 2 and k:
            p[k] = p[k - 1] + [cfg.neighbour_radius(), 0.0]  # a pair at the neighbour radius
        elif pick == 3 and k:
            p[k] = p[k - 1]  # coincident
    return p


CONFIGS = [BarrierConfig(), BarrierConfig(safety_distance=0.15, gamma=150.0),
           BarrierConfig(bounds=(-1.0, 1.2, -0.7, 0.9), wall_margin=0.05, class_k="linear", gamma=20.0)]


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(0, SMALL_ROBOTS), which=st.integers(0, len(CONFIGS) - 1),
       spread=st.sampled_from([1.0, 0.2, 1.05]))
def test_wall_rows_one_rectangle_same_bits_as_per_robot(seed: int, n: int, which: int, spread: float) -> None:
    cfg = CONFIGS[which]
    p = _points(seed, n, cfg, spread)
    per_robot = np.tile(np.asarray(cfg.bounds, dtype=float), (n, 1))
    assert _same_rows(wall_rows(p, cfg), wall_rows(p, cfg, per_robot))


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(0, SMALL_ROBOTS), which=st.integers(0, len(CONFIGS) - 1),
       spread=st.sampled_from([1.0, 0.15]))
def test_dense_pair_rows_same_bits_as_tree(seed: int, n: int, which: int, spread: float) -> None:
    cfg = CONFIGS[which]
    p = _points(seed, n, cfg, spread)
    tree = cKDTree(p) if n else None
    assert _same_rows(pair_rows(p, cfg), pair_rows(p, cfg, tree))


def _wheel_rows_stacked(poses: np.ndarray, params: UnicycleParams, n_obs: int) -> Rows:
    """wheel_limit_rows as it was written before (stacked arrays): the reference."""
    n = poses.shape[0]
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    k = params.axle_length / (2 * params.lookahead)
    g_right = np.stack([c - k * s, s + k * c], axis=1) / params.wheel_radius
    g_left = np.stack([c + k * s, s - k * c], axis=1) / params.wheel_radius
    g = np.stack([g_right, -g_right, g_left, -g_left], axis=1).reshape(-1, 2)
    norm = np.sqrt(1 + k * k) / params.wheel_radius
    i = np.repeat(np.arange(n, dtype=np.int64), 4)
    side = np.tile(np.arange(4, dtype=np.int64), n)
    key = n * n + 4 * n + n * n_obs + 4 * i + side
    return Rows(i, np.full_like(i, -1), g / norm, np.zeros_like(g), np.full(4 * n, params.max_wheel_speed / norm),
                np.full(4 * n, np.inf), np.full(4 * n, 3, dtype=np.int8), key)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(0, SMALL_ROBOTS), n_obs=st.integers(0, 3),
       lookahead=st.sampled_from([0.03, 0.05, 0.011]), axes=st.booleans())
def test_wheel_limit_rows_same_bits_as_stacked(seed: int, n: int, n_obs: int, lookahead: float, axes: bool) -> None:
    rng = np.random.default_rng(seed)
    poses = np.column_stack([rng.uniform(-1.5, 1.5, (n, 2)), rng.uniform(-7.0, 7.0, n)])
    if axes:  # headings on the axes: zeros and signed zeros in the coefficients
        poses[:, 2] = rng.choice([0.0, -0.0, np.pi / 2, -np.pi / 2, np.pi, -np.pi], n)
    params = UnicycleParams(lookahead=lookahead)
    assert _same_rows(wheel_limit_rows(poses, params, n_obs), _wheel_rows_stacked(poses, params, n_obs))


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, SMALL_ROBOTS), m=st.integers(1, 40))
def test_working_residuals_are_row_slack(seed: int, n: int, m: int) -> None:
    """The certificate's shortcut: a working set of rows only has the residuals of those rows' slack, up to the
    sign of a zero (the certificate reads only their magnitudes)."""
    rng = np.random.default_rng(seed)
    i = rng.integers(0, n, m).astype(np.int64)
    j = rng.integers(0, n, m).astype(np.int64)
    single = rng.random(m) < 0.4
    j[single] = -1
    ci = rng.normal(0.0, 1.0, (m, 2)) * (rng.random((m, 1)) < 0.9)  # some zero rows
    cj = np.where(single[:, None], 0.0, rng.normal(0.0, 1.0, (m, 2)))
    b = rng.normal(0.0, 0.1, m)
    rows = Rows(i, j, ci, cj, b, np.zeros(m), np.zeros(m, dtype=np.int8), np.arange(m, dtype=np.int64))
    u = rng.normal(0.0, 0.2, (n, 2)) * (rng.random((n, 1)) < 0.8)  # some robots at rest: zero products
    idx = np.flatnonzero(rng.random(m) < 0.5)
    work = _Working(rows.i[idx], rows.jj[idx], rows.ci[idx], rows.cj[idx], rows.b[idx], n)
    assert _same(np.abs(work.A(u) - work.b), np.abs((rows.lhs(u) - rows.b)[idx]))


def test_concat_of_one_part_same_bits() -> None:
    rng = np.random.default_rng(3)
    p = rng.uniform(-0.3, 0.3, (6, 2))
    part = pair_rows(p, BarrierConfig())
    assert part.m
    one = Rows.concat([Rows.empty(), part, wall_rows(p, BarrierConfig())])
    full = Rows(*(np.concatenate([getattr(q, f) for q in (Rows.empty(), part)]) for f in _FIELDS))
    assert _same_rows(one, full)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, SMALL_ROBOTS), which=st.integers(0, len(CONFIGS) - 1))
def test_filter_one_rectangle_same_bits_as_per_robot(seed: int, n: int, which: int) -> None:
    """The whole filter (rows, answer, every diagnostic but the time) with the config's rectangle and with the
    same rectangle given per robot, over a few closed-loop steps (warm starts included)."""
    cfg = CONFIGS[which]
    p = _points(seed, n, cfg, 0.95)
    rng = np.random.default_rng(seed + 1)
    goal = rng.uniform(-1.0, 1.0, (n, 2))
    a, b = SafetyFilter(cfg, robots=n), SafetyFilter(cfg, robots=n)
    per_robot = np.tile(np.asarray(cfg.bounds, dtype=float), (n, 1))
    for _ in range(4):
        nominal = 1.5 * (goal - p)
        ua, da = a.filter(p, nominal)
        ub, db = b.filter(p, nominal, robot_bounds=per_robot)
        assert _same(ua, ub)
        for field in dataclasses.fields(da):
            x, y = getattr(da, field.name), getattr(db, field.name)
            if field.name != "solve_time_s":
                assert _same(x, y) if isinstance(x, np.ndarray) else (x == y or (x != x and y != y)), field.name
        p = p + 0.033 * ua
