"""Anytime barrier settings (issue 27 item 1): budgets are refused with a message naming them."""
from __future__ import annotations

import pytest

from swarmdeck.safety import BarrierConfig


@pytest.mark.parametrize("kwargs, name", [
    ({"work_budget": 0}, "work_budget"), ({"work_budget": True}, "work_budget"),
    ({"work_budget": 2.5}, "work_budget"), ({"active_set_max_solves": -1}, "active_set_max_solves"),
    ({"time_budget_s": 0.0}, "time_budget_s"), ({"time_budget_s": float("nan")}, "time_budget_s"),
    ({"distributed_second_pass": 1}, "distributed_second_pass"), ({"mode": "fast"}, "mode"),
])
def test_bad_budget_is_refused_by_name(kwargs: dict, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        BarrierConfig(**kwargs)


def test_anytime_settings_round_trip() -> None:
    cfg = BarrierConfig(mode="anytime", work_budget=40, active_set_max_solves=24, time_budget_s=0.02)
    assert BarrierConfig.from_dict(cfg.to_dict()) == cfg
    assert cfg.anytime_for(10_000) and not cfg.distributed_for(10_000)
    auto = BarrierConfig(mode="auto", distributed_above=200)
    assert auto.anytime_for(200) and auto.distributed_for(201) and not auto.anytime_for(201)
