"""Anytime barrier (issue 27 item 1): the budget covers the whole call, clarabel included.

On a pinned dense scene (the crossing at N = 150 after 30 ticks of jamming) a fresh anytime
filter whose warm stage may spend 1 factorisation and whose call may spend 6 in all runs out
inside clarabel cold (its ``max_iter`` is what the budget has left): on every run at the same
count, with the distributed floor on the same rows as the answer (certified: every row, every
speed bound), the diagnostics saying so. With the budget that the exact solve needs, the answer
is the optimum.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from swarmdeck.safety import SafetyFilter
from swarmdeck.safety import filter as filter_module
from swarmdeck.safety.constraints import barrier_rows
from swarmdeck.safety.scenes import jammed_crossing, toward

N = 150


@pytest.fixture(scope="module")
def jammed():
    """(cfg, points, nominal) of the jammed crossing at tick 30 (clarabel's trajectory)."""
    cfg, x, goals = jammed_crossing(N, 7, 30)
    return cfg, x, toward(goals, x, cfg.max_speed)


def test_the_budget_runs_out_inside_clarabel_and_the_floor_answers(monkeypatch, jammed) -> None:
    cfg, x, nom = jammed
    capped = dataclasses.replace(cfg, mode="anytime", active_set_max_solves=1, work_budget=6)
    asked: list[int] = []
    real = filter_module.solve_qp

    def spy(*args, **kwargs):
        res = real(*args, **kwargs)
        asked.append(kwargs["max_iter"])
        assert res.iterations <= kwargs["max_iter"]
        return res

    monkeypatch.setattr(filter_module, "solve_qp", spy)
    u1, d1 = SafetyFilter(capped).filter(x, nom)
    u2, d2 = SafetyFilter(capped).filter(x, nom)
    monkeypatch.undo()
    assert asked and all(0 < m <= 6 for m in asked), asked  # clarabel got only what the budget had left
    assert d1.ok and d1.answer == "floor" and d1.method == "distributed floor", d1.status
    assert "clarabel" in d1.status and d1.gap is None
    assert d1.work == d2.work == 6 and np.array_equal(u1, u2)
    rows = barrier_rows(x, cfg)
    assert np.all(rows.lhs(u1) <= rows.b + 2e-10)
    assert np.all(np.einsum("kd,kd->k", u1, u1) <= cfg.max_speed**2)
    exact, de = SafetyFilter(cfg).filter(x, nom)
    assert de.ok and de.work > 6
    ub, db = SafetyFilter(dataclasses.replace(capped, work_budget=de.work + 60)).filter(x, nom)
    assert db.answer == "optimum"
    np.testing.assert_allclose(ub, exact, rtol=0, atol=1e-4 if db.method == "clarabel" else 1e-9)
