"""Configuration: the pruning radii are where rows start to bind; bad values are refused."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.safety import BarrierConfig, UnicycleParams


@pytest.mark.parametrize("cfg", [BarrierConfig(), BarrierConfig(class_k="linear", gamma=20.0),
                                 BarrierConfig(safety_distance=0.25, gamma=150.0, max_speed=0.15)])
def test_bind_distance_is_where_rows_can_bind(cfg: BarrierConfig) -> None:
    d = cfg.pair_bind_distance()
    def bound(r):
        return cfg.gamma * cfg.kappa(r * r - cfg.safety_distance**2)

    assert bound(d) == pytest.approx(4 * d * cfg.max_speed, rel=1e-9)
    assert bound(d * 1.01) > 4 * d * 1.01 * cfg.max_speed
    assert cfg.neighbour_radius() > d
    c = cfg.wall_bind_clearance()
    assert cfg.wall_gain * cfg.gamma * cfg.kappa(c) == pytest.approx(cfg.max_speed, rel=1e-9)


def test_rps_numbers() -> None:
    """REFERENCE.md §3: with γ = 100, D_s = 0.17 a pair row binds only closer than ≈ 0.42 m."""
    assert BarrierConfig().pair_bind_distance() == pytest.approx(0.42, abs=0.01)
    assert BarrierConfig().wall_radius() == pytest.approx(0.26, abs=0.01)
    assert UnicycleParams().max_linear_speed == pytest.approx(0.2)


@pytest.mark.parametrize("kwargs", [dict(safety_distance=0), dict(gamma=-1), dict(class_k="quadratic"),
                                    dict(max_speed=0), dict(bounds=(-0.05, 0.05, -1, 1)),
                                    dict(bounds=(0, 1, 0)), dict(solver="cvxopt"), dict(bounds=(0, np.inf, 0, 1))])
def test_bad_config_refused(kwargs) -> None:
    with pytest.raises(ValueError, match="BarrierConfig"):
        BarrierConfig(**kwargs)


def test_bad_params_refused() -> None:
    with pytest.raises(ValueError, match="wheel_radius"):
        UnicycleParams(wheel_radius=0)


def test_from_dict_round_trip_and_errors() -> None:
    cfg = BarrierConfig(gamma=150.0, class_k="linear", bounds=(-1.0, 1.0, -0.5, 0.5))
    assert BarrierConfig.from_dict(cfg.to_dict()) == cfg
    with pytest.raises(ValueError, match="unknown setting"):
        BarrierConfig.from_dict({"gama": 3})
    with pytest.raises(ValueError, match="bounds"):
        BarrierConfig.from_dict({"bounds": "wide"})
