"""Optimality: the pruned, structured filter agrees with an independent dense all-pairs solve.

The oracle below is written from REFERENCE.md §3 alone: rps-form unnormalised
rows for every pair and every wall, second-order cones for the speed bound,
solved with clarabel at tight tolerances.
"""
from __future__ import annotations

import clarabel
import numpy as np
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.safety import BarrierConfig, SafetyFilter
from swarmdeck.safety.scenes import grid_scene


def oracle(x: np.ndarray, uh: np.ndarray, cfg: BarrierConfig) -> np.ndarray:
    n = x.shape[0]
    A_rows, b = [], []
    for i in range(n):
        for j in range(i + 1, n):
            e = x[i] - x[j]
            h = e @ e - cfg.safety_distance**2
            row = np.zeros(2 * n)
            row[2 * i:2 * i + 2] = -2 * e
            row[2 * j:2 * j + 2] = 2 * e
            A_rows.append(row)
            b.append(cfg.gamma * cfg.kappa(h))
    x_min, x_max, y_min, y_max = cfg.bounds
    m = cfg.margin
    g = cfg.wall_gain * cfg.gamma
    for i in range(n):
        for axis, sign, wall in ((0, 1, x_max), (0, -1, x_min), (1, 1, y_max), (1, -1, y_min)):
            row = np.zeros(2 * n)
            row[2 * i + axis] = sign
            A_rows.append(row)
            b.append(g * cfg.kappa(sign * (wall - x[i, axis]) - m))
    soc = np.zeros((3 * n, 2 * n))
    for i in range(n):
        soc[3 * i + 1, 2 * i] = -1
        soc[3 * i + 2, 2 * i + 1] = -1
    A = sp.csc_matrix(np.vstack([np.array(A_rows), soc]))
    bb = np.concatenate([b, np.tile([cfg.max_speed, 0, 0], n)])
    s = clarabel.DefaultSettings()
    s.verbose = False
    s.tol_gap_abs = s.tol_gap_rel = s.tol_feas = 1e-10
    solver = clarabel.DefaultSolver(sp.identity(2 * n, format="csc"), -uh.reshape(-1), A, bb,
                                    [clarabel.NonnegativeConeT(len(b))] + [clarabel.SecondOrderConeT(3)] * n, s)
    sol = solver.solve()
    assert str(sol.status) == "Solved"
    return np.array(sol.x).reshape(n, 2)


@settings(max_examples=40, deadline=None)
@given(n=st.integers(2, 40), seed=st.integers(0, 2**31 - 1), crowd=st.booleans())
def test_matches_dense_all_pairs(n: int, seed: int, crowd: bool) -> None:
    rng = np.random.default_rng(seed)
    cfg = BarrierConfig(bounds=(-0.8, 0.8, -0.6, 0.6)) if crowd else BarrierConfig()
    x, nominal = grid_scene(n, rng, cfg)
    f = SafetyFilter(cfg)
    u, diag = f.filter(x, nominal)
    assert diag.ok, diag.status
    np.testing.assert_allclose(u, oracle(x, nominal, cfg), atol=1e-5, rtol=0)


def test_active_set_and_clarabel_paths_agree() -> None:
    """Both solver paths of the filter, and the warm-started active set, give the same answer."""
    rng = np.random.default_rng(2)
    auto, ipm = SafetyFilter(), SafetyFilter(BarrierConfig(solver="clarabel"))
    methods = set()
    for _ in range(15):
        x, nominal = grid_scene(60, rng)
        for _ in range(2):  # the second call is warm-started
            u1, d1 = auto.filter(x, nominal)
            u2, d2 = ipm.filter(x, nominal)
            assert d1.ok and d2.ok
            methods.add(d1.method)
            np.testing.assert_allclose(u1, u2, atol=1e-5, rtol=0)
    assert "active-set" in methods


def test_obstacles_are_fixed_points() -> None:
    """A robot driving at a fixed obstacle point: the robot alone keeps D_s (the obstacle never 'moves')."""
    cfg = BarrierConfig()
    x = np.array([[0.0, 0.0]])
    obstacle = np.array([[0.25, 0.0]])
    f = SafetyFilter(cfg)
    for _ in range(400):
        u, diag = f.filter(x, np.array([[0.2, 0.0]]), obstacles=obstacle)
        assert diag.ok
        x = x + u * 0.033
    d = np.linalg.norm(x[0] - obstacle[0])
    assert cfg.safety_distance - 1e-3 <= d < 0.23  # closed in, never inside D_s (cubic κ: slow final approach)
    assert abs(diag.min_obstacle_distance - d) < 0.01
