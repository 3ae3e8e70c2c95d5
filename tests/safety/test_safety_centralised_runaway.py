"""A plain ``BarrierConfig()`` (mode "centralised", no caps set) has no runaway stage (issue 27 item 1).

Before, with ``active_set_max_solves=None`` an active-set stage had no bound on its Gram
factorisations (the dense crossing's warm paths and polish spent up to 2 s on one tick at
N = 1000, 13-27× clarabel's worst). Now every stage is held to ``_RUNAWAY_SOLVES`` (60): above
what any stage that certifies in the pinned tests spends, so their answers are unchanged, while
a degenerate stage gives up and clarabel answers. Counted, never timed. The spy calls through.
"""
from __future__ import annotations

import numpy as np

from swarmdeck.safety import SafetyFilter
from swarmdeck.safety import filter as filter_module
from swarmdeck.safety.constraints import barrier_rows
from swarmdeck.safety.scenes import crossing_scene, toward


def test_every_active_set_stage_is_capped_in_centralised_mode(monkeypatch) -> None:
    cfg, x, goals = crossing_scene(200, np.random.default_rng(0))
    assert cfg.mode == "centralised" and cfg.active_set_max_solves is None
    asked: list[tuple[int | None, int]] = []
    real = filter_module.solve_active_set

    def spy(*args, **kwargs):
        res = real(*args, **kwargs)
        asked.append((kwargs.get("max_solves"), res.solves))
        return res

    monkeypatch.setattr(filter_module, "solve_active_set", spy)
    flt = SafetyFilter(cfg)
    for _ in range(12):
        u, d = flt.filter(x, toward(goals, x, cfg.max_speed))
        assert d.ok and d.answer == "optimum", d.status
        rows = barrier_rows(x, cfg)
        assert np.all(rows.lhs(u) <= rows.b + 1e-7)
        x = x + u * cfg.dt
    assert asked
    cap = filter_module._RUNAWAY_SOLVES
    assert all(c is not None and c <= cap and spent <= cap for c, spent in asked), asked
