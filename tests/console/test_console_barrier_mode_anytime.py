"""The console's [safety] mode offers every barrier mode the filter has: "anytime" (the optimum within the
per-tick work budget, else the certified distributed answer) was refused by the operator's parameter schema."""
from __future__ import annotations

import pytest

from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig, SafetyParams


def test_anytime_is_a_console_barrier_mode_and_the_filter_runs_it() -> None:
    assert SafetyParams(mode="anytime").mode == "anytime"
    loop = ControlLoop(LoopConfig(n_robots=6, safety=SafetyParams(mode="anytime")))
    try:
        frame = loop.tick()
        assert frame.params["barrier_mode"] == "anytime"
        assert loop._filter.config.mode == "anytime"  # the loop's barrier, with the pipelines' work budget
        assert loop._filter.config.work_budget is not None
    finally:
        loop.close()
    with pytest.raises(ValueError, match="mode"):
        SafetyParams(mode="fastest")
