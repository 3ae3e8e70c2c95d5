"""Anytime barrier (issue 27 item 1): a failing capped stage costs a bounded share of clarabel.

``BarrierConfig.warm_share`` (on in the pipelines): beyond 200 active rows the warm
paths of a call may spend at most that fraction of the iterations clarabel cold took last time
(clarabel's polish keeps its own ≤ 4), and a stage that spent its cap and failed is skipped on the
next 1, 3, 7, … calls. Counted, never
timed, so the pattern is the same on every run. On a pinned jammed crossing (N = 150 after 30
ticks) the spies below call through to the real solvers and only record what they were asked.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from swarmdeck.safety import SafetyFilter, dual_ascent
from swarmdeck.safety import filter as filter_module
from swarmdeck.safety.config import BarrierConfig, pipeline_defaults
from swarmdeck.safety.constraints import barrier_rows
from swarmdeck.safety.scenes import jammed_crossing, toward

N = 150
TICKS = 16


@pytest.fixture(scope="module")
def jammed():
    """(cfg, points, goals) of the jammed crossing at tick 30 (clarabel's trajectory)."""
    cfg, x, goals = jammed_crossing(N, 7, 30)
    return cfg, x, goals


def _warm_tries(monkeypatch, cfg: BarrierConfig, x: np.ndarray, goals: np.ndarray) -> list[int]:
    """The calls (0-based) on which the closed-loop warm paths ran, over TICKS closed-loop ticks."""
    calls: list[int] = []
    tick = [-1]  # the constructor's compile warm-up calls it too
    real = dual_ascent.ascend

    def spy(*args, **kwargs):
        calls.append(tick[0])
        return real(*args, **kwargs)

    monkeypatch.setattr(dual_ascent, "ascend", spy)
    flt = SafetyFilter(cfg)
    for t in range(TICKS):
        tick[0] = t
        u, d = flt.filter(x, toward(goals, x, cfg.max_speed))
        assert d.ok and d.answer == "optimum", d.status
        x = x + u * cfg.dt
    return sorted({t for t in calls if t >= 0})


def test_a_failing_warm_stage_backs_off_1_3_7_ticks(monkeypatch, jammed) -> None:
    cfg, x, goals = jammed
    # cold_dual off: tick 0 goes to clarabel at once (the cold prediction would shift the pattern by one tick)
    capped = dataclasses.replace(cfg, mode="anytime", active_set_max_solves=1, cold_dual=False)
    # one factorisation never certifies this jam: without warm_share the warm paths are tried every other tick
    assert _warm_tries(monkeypatch, capped, x, goals) == list(range(1, TICKS, 2))
    shared = dataclasses.replace(capped, warm_share=0.25)
    assert _warm_tries(monkeypatch, shared, x, goals) == [1, 3, 7, 15]


def test_the_warm_paths_spend_at_most_their_share_of_clarabels_iterations(monkeypatch, jammed) -> None:
    cfg, x, goals = jammed
    share = 0.1
    # cold_dual off: with it the cold prediction certifies tick 0 and the warm paths every tick after
    # (clarabel never runs, so there is no share to apply)
    shared = dataclasses.replace(cfg, mode="anytime", active_set_max_solves=12, warm_share=share, cold_dual=False)
    log: list[tuple[str, int | None, int]] = []  # (solver, cap asked, work spent)
    real_as, real_qp = filter_module.solve_active_set, filter_module.solve_qp

    def spy_as(*args, **kwargs):
        res = real_as(*args, **kwargs)
        log.append(("active set", kwargs.get("max_solves"), res.solves))
        return res

    def spy_qp(*args, **kwargs):
        res = real_qp(*args, **kwargs)
        if kwargs.get("discs") is None:  # cold (the pruned warm path passes its discs)
            log.append(("clarabel", kwargs.get("max_iter"), res.iterations))
        return res

    monkeypatch.setattr(filter_module, "solve_active_set", spy_as)
    monkeypatch.setattr(filter_module, "solve_qp", spy_qp)
    flt, exact = SafetyFilter(shared), SafetyFilter(cfg)
    cold = None  # clarabel's last cold iteration count
    checked = 0
    for _ in range(TICKS):
        nom = toward(goals, x, cfg.max_speed)
        log.clear()
        u, d = flt.filter(x, nom)
        assert d.ok and d.answer == "optimum", d.status
        allowed = None if cold is None else max(1, int(share * cold))  # from the last tick's cold solve
        polishing = False  # active-set calls after the cold clarabel solve are its polish: ≤ 4 of their own
        for solver, cap, spent in log:
            if solver == "active set" and polishing:
                assert cap is not None and cap <= 4 and spent <= 4, (cap, spent)
            elif solver == "active set" and allowed is not None:
                assert cap is not None and cap <= allowed and spent <= allowed, (cap, spent, cold)
                checked += 1
            if solver == "clarabel" and spent:
                cold, polishing = spent, True
        # the answer is the optimum: exactly when certified, to clarabel's tolerance when not polished
        monkeypatch.setattr(filter_module, "solve_active_set", real_as)
        monkeypatch.setattr(filter_module, "solve_qp", real_qp)
        ue, de = exact.filter(x, nom)
        monkeypatch.setattr(filter_module, "solve_active_set", spy_as)
        monkeypatch.setattr(filter_module, "solve_qp", spy_qp)
        assert de.ok
        np.testing.assert_allclose(u, ue, rtol=0, atol=1e-9 if d.method != "clarabel" else 1e-4)
        rows = barrier_rows(x, cfg)
        assert np.all(rows.lhs(u) <= rows.b + (1e-7 if d.method == "clarabel" else 2e-10))
        assert np.all(np.einsum("kd,kd->k", u, u) <= cfg.max_speed**2)
        x = x + u * cfg.dt
    assert checked >= 3  # the share was applied, not just the fixed cap


def test_warm_share_is_validated_and_on_in_the_pipelines() -> None:
    assert pipeline_defaults()["warm_share"] == 0.1
    assert BarrierConfig.from_dict({"warm_share": 0.5}).warm_share == 0.5
    for bad in (0, -0.1, float("nan"), "a", True):
        with pytest.raises(ValueError, match="warm_share"):
            BarrierConfig(warm_share=bad)
