"""Non-finite settings and overflowing rows stop the robots; they never drop out of the QP (issue 14, items 1–2)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from swarmdeck.devices import Arena
from swarmdeck.safety import BarrierConfig, SafetyFilter, UnicycleParams, UnicycleSafetyFilter

_FLOAT_FIELDS = ["safety_distance", "gamma", "max_speed", "wall_margin", "wall_gain", "dt",
                 "recovery_speed", "recovery_weight", "clarabel_tol"]


@pytest.mark.parametrize("name", _FLOAT_FIELDS)
@pytest.mark.parametrize("value", [math.inf, -math.inf, math.nan])
def test_non_finite_setting_refused(name: str, value: float) -> None:
    with pytest.raises(ValueError, match=f"BarrierConfig: {name}"):
        BarrierConfig(**{name: value})


@pytest.mark.parametrize("kwargs", [dict(gamma="100"), dict(recovery="yes"), dict(max_active_set_iterations=2.5),
                                    dict(wall_margin=-0.01), dict(max_speed=True), dict(active_set_max_rows=-1),
                                    dict(warm_dual_sweeps=-1), dict(warm_dual_iterations=0), dict(warm_dual_sweeps=1.5)])
def test_mistyped_or_out_of_range_setting_refused(kwargs) -> None:
    with pytest.raises(ValueError, match="BarrierConfig"):
        BarrierConfig(**kwargs)


def test_toml_inf_refused_by_from_dict() -> None:
    with pytest.raises(ValueError, match="gamma"):
        BarrierConfig.from_dict({"gamma": float("inf")})


@pytest.mark.parametrize("name", ["wheel_radius", "axle_length", "max_wheel_speed", "lookahead"])
def test_unicycle_params_finite(name: str) -> None:
    with pytest.raises(ValueError, match=name):
        UnicycleParams(**{name: math.inf})


def test_issue_example_no_longer_passes_the_collision() -> None:
    """γ = inf made the pair row's bound inf·0 = NaN: the row vanished and the colliding nominal came back."""
    with pytest.raises(ValueError, match="gamma"):
        SafetyFilter(BarrierConfig(gamma=math.inf))


def test_nan_row_bound_fail_stops() -> None:
    """Finite but huge gains overflow: wall_gain·γ = inf, and at clearance 0 the bound is inf·0 = NaN."""
    cfg = BarrierConfig(gamma=1e300, wall_gain=1e300)
    x_max = cfg.bounds[1] - cfg.margin
    u, diag = SafetyFilter(cfg).filter([[x_max, 0.0]], [[0.2, 0.0]])  # on the margin, driving out
    assert not diag.ok and "non-finite" in diag.status and "wall" in diag.status, diag.status
    assert np.array_equal(u, np.zeros((1, 2)))


@pytest.mark.parametrize("big", [1e155, 1e200, -1e300, 1e7])
def test_huge_coordinates_fail_stop(big: float) -> None:
    x = np.array([[0.0, 0.0], [big, 0.3]])
    u, diag = SafetyFilter().filter(x, [[0.1, 0.0], [0.0, 0.0]])
    assert not diag.ok and "coordinates" in diag.status, diag.status
    assert np.array_equal(u, np.zeros((2, 2)))
    v, w, diag = UnicycleSafetyFilter().filter([[0.0, 0.0, 0.0], [0.3, big, 1.0]], [0.1, 0.1], [0.0, 0.0])
    assert not diag.ok and "coordinates" in diag.status, diag.status
    assert np.array_equal(v, np.zeros(2)) and np.array_equal(w, np.zeros(2))


def test_arena_reports_huge_coordinates() -> None:
    arena = Arena(initial_conditions=np.array([[0.0, 0.0, 0.0], [1e155, 0.0, 0.0]]))
    arena.step()  # did raise ValueError from cKDTree
    rep = arena.report().to_dict()["safety"]
    assert rep["failures"] == 1
    assert any("coordinates" in reason for reason in rep["failure_reasons"]), rep
