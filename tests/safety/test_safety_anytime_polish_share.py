"""Anytime barrier (issue 27 item 1): clarabel's polish costs a bounded share of clarabel on many rows.

With ``warm_share`` (on in the pipelines), once clarabel's answer holds more than 200 rows near
their bound the certified polish from them may spend at most ``warm_share`` of the iterations
that cold solve took (at least 1), not the fixed 4: on the dense crossing at N = 200 the polish
needs 56-128 Gram factorisations or certifies in one, so four failed ones cost half a clarabel
solve on top of it (bench/RESULTS.md, "barrier: anytime"). Counted, never timed. The spy calls
through to the real solver and records only what the polish was asked and what it spent.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from swarmdeck.safety import SafetyFilter
from swarmdeck.safety import filter as filter_module
from swarmdeck.safety.config import pipeline_defaults
from swarmdeck.safety.constraints import barrier_rows
from swarmdeck.safety.scenes import crossing_scene, jammed_crossing, toward

N = 200


@pytest.fixture(scope="module")
def jammed():
    """(cfg, points, goals) of the crossing at N = 200 after 20 ticks (clarabel's trajectory)."""
    cfg, x, goals = jammed_crossing(N, 0, 20)
    return cfg, x, goals


def test_the_polish_spends_at_most_its_share_of_clarabels_iterations(monkeypatch, jammed) -> None:
    cfg, x, goals = jammed
    share = pipeline_defaults()["warm_share"]
    assert isinstance(share, float)
    flt = SafetyFilter(dataclasses.replace(cfg, **{**pipeline_defaults(), "mode": "anytime"}))
    log: list[tuple[str, int | None, int]] = []
    real_as, real_qp = filter_module.solve_active_set, filter_module.solve_qp

    def spy_as(rows, U, max_speed, warm_rows=None, *args, **kwargs):
        res = real_as(rows, U, max_speed, warm_rows, *args, **kwargs)
        near = -1 if warm_rows is None else int(np.sum(warm_rows))
        log.append(("active set", kwargs.get("max_solves"), res.solves, near))
        return res

    def spy_qp(*args, **kwargs):
        res = real_qp(*args, **kwargs)
        if kwargs.get("discs") is None:
            log.append(("clarabel", kwargs.get("max_iter"), res.iterations, 0))
        return res

    monkeypatch.setattr(filter_module, "solve_active_set", spy_as)
    monkeypatch.setattr(filter_module, "solve_qp", spy_qp)
    polished = 0
    for _ in range(4):
        nom = toward(goals, x, cfg.max_speed)
        log.clear()
        u, d = flt.filter(x, nom)
        assert d.ok and d.answer == "optimum", d.status
        cold = None
        for solver, cap, spent, near in log:
            if solver == "clarabel" and spent:
                cold = spent
            elif solver == "active set" and cold is not None:  # the polish, after the cold solve
                assert near > 200
                allowed = max(1, int(share * cold))
                assert cap is not None and cap <= allowed and spent <= allowed, (cap, spent, cold)
                polished += 1
        rows = barrier_rows(x, cfg)
        assert np.all(rows.lhs(u) <= rows.b + 1e-7)
        assert np.all(np.einsum("kd,kd->k", u, u) <= cfg.max_speed**2)
        x = x + u * cfg.dt
    assert polished >= 1  # the polish ran on many rows and was held to its share


def test_a_cold_prediction_on_many_rows_spends_at_most_its_share(monkeypatch) -> None:
    """The crossing's first tick at N = 200 (no warm start, no clarabel count yet): the cold dual
    prediction holds > 200 rows, so its active set gets warm_share of 25 assumed clarabel iterations."""
    cfg, x, goals = crossing_scene(N, np.random.default_rng(0))
    share = pipeline_defaults()["warm_share"]
    assert isinstance(share, float)
    caps: list[int | None] = []
    real = filter_module.solve_active_set

    def spy(*args, **kwargs):
        caps.append(kwargs.get("max_solves"))
        return real(*args, **kwargs)

    monkeypatch.setattr(filter_module, "solve_active_set", spy)
    u, d = SafetyFilter(dataclasses.replace(cfg, **{**pipeline_defaults(), "mode": "anytime"})).filter(
        x, toward(goals, x, cfg.max_speed))
    assert d.ok and d.answer == "optimum", d.status
    allowed = max(1, int(share * filter_module._COLD_ITERS_GUESS))
    assert caps and caps[0] is not None and caps[0] <= allowed, caps  # the cold prediction's active set
