"""Fail-stop: malformed input, infeasible QPs and unconverged solves stop every robot with a reason."""
from __future__ import annotations

import json

import numpy as np
import pytest

from swarmdeck.safety import BarrierConfig, SafetyFilter, UnicycleSafetyFilter
from swarmdeck.safety.scenes import grid_scene


def check_stopped(u: np.ndarray, diag, n: int, reason: str) -> None:
    assert u.shape == (n, 2)
    assert np.array_equal(u, np.zeros((n, 2)))
    assert not diag.ok and diag.method == "fail-stop"
    assert reason in diag.status, diag.status
    json.dumps(diag.to_dict(), allow_nan=False)


@pytest.mark.parametrize("field,value", [("points", np.nan), ("points", np.inf), ("nominal", np.nan),
                                         ("nominal", -np.inf)])
def test_non_finite_input(field: str, value: float) -> None:
    x, nominal = grid_scene(6, np.random.default_rng(0))
    args = {"points": x.copy(), "nominal": nominal.copy()}
    args[field][2, 1] = value
    u, diag = SafetyFilter().filter(args["points"], args["nominal"])
    check_stopped(u, diag, 6, "NaN or inf")


@pytest.mark.parametrize("points,nominal,n", [
    (np.zeros((3, 2)), np.zeros((2, 2)), 2),
    (np.zeros((3, 3)), np.zeros((3, 3)), 3),
    (np.zeros(4), np.zeros(4), 4),
    ([["a", "b"]], [[0.0, 0.0]], 1),
])
def test_bad_shapes(points, nominal, n) -> None:
    u, diag = SafetyFilter().filter(points, nominal)
    check_stopped(u, diag, n, "invalid input")


def test_bad_obstacles() -> None:
    x, nominal = grid_scene(3, np.random.default_rng(0))
    u, diag = SafetyFilter().filter(x, nominal, obstacles=np.zeros((2, 3)))
    check_stopped(u, diag, 3, "obstacles")


def squeezed_line() -> tuple[np.ndarray, BarrierConfig]:
    """Three robots in a line in a corridor too narrow for them: outer ones beyond the wall
    margins, every pair closer than D_s. The plain rows demand that the left robot move right,
    the right one move left, and both pairs separate: infeasible for any γ."""
    return np.array([[-0.14, 0.0], [0.0, 0.0], [0.14, 0.0]]), BarrierConfig(bounds=(-0.2, 0.2, -1.0, 1.0))


def test_infeasible_without_recovery_stops() -> None:
    x, cfg = squeezed_line()
    for solver in ("auto", "clarabel"):
        f = SafetyFilter(BarrierConfig(bounds=cfg.bounds, recovery=False, solver=solver))
        u, diag = f.filter(x, np.array([[0.1, 0.0], [0.0, 0.1], [-0.1, 0.0]]))
        check_stopped(u, diag, 3, "infeasible")


def test_coincident_points_without_recovery_stop() -> None:
    x = np.array([[0.0, 0.0], [0.0, 0.0], [0.5, 0.5]])
    u, diag = SafetyFilter(BarrierConfig(recovery=False)).filter(x, np.full((3, 2), 0.05))
    check_stopped(u, diag, 3, "infeasible")


def test_iteration_limit_stops() -> None:
    x, nominal = grid_scene(20, np.random.default_rng(1))
    f = SafetyFilter(BarrierConfig(solver="clarabel", clarabel_max_iter=2))
    u, diag = f.filter(x, nominal)
    check_stopped(u, diag, 20, "iteration limit")


def test_recovers_after_failure() -> None:
    x, nominal = grid_scene(10, np.random.default_rng(4))
    f = SafetyFilter()
    bad = nominal.copy()
    bad[0, 0] = np.nan
    assert not f.filter(x, bad)[1].ok
    u, diag = f.filter(x, nominal)
    assert diag.ok and np.all(np.isfinite(u))


def test_unicycle_bad_input_stops() -> None:
    f = UnicycleSafetyFilter()
    v, w, diag = f.filter(np.zeros((2, 3)), np.zeros(3), np.zeros(2))
    assert not diag.ok and np.array_equal(v, np.zeros(2)) and np.array_equal(w, np.zeros(2))
    v, w, diag = f.filter(np.array([[0, 0, np.nan], [1, 0, 0]]), np.zeros(2), np.zeros(2))
    assert not diag.ok and "NaN" in diag.status
