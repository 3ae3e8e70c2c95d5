"""Anytime barrier (issue 27 item 1): the work cap is hit deterministically and the fallback is certified.

A pinned dense scene (the crossing at N = 150 after 30 ticks of jamming): a budget of a few
factorisations runs out on every run at the same count, and the answer is the distributed floor
on the same rows, identical on every run, meeting every row; the warm cap alone
(``active_set_max_solves``) falls back to clarabel cold and returns its optimum (polished by the
active set within the same cap, else clarabel's own answer, accepted to 1e-7 m/s as always).
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from swarmdeck.safety import SafetyFilter
from swarmdeck.safety.constraints import barrier_rows
from swarmdeck.safety.scenes import crossing_scene, toward

N = 150


@pytest.fixture(scope="module")
def jammed():
    """(cfg, the warm centralised filter, points, nominal) of the jammed crossing at tick 30."""
    cfg, x, goals = crossing_scene(N, np.random.default_rng(7))
    flt = SafetyFilter(cfg)
    for _ in range(30):
        u, d = flt.filter(x, toward(goals, x, cfg.max_speed))
        assert d.ok
        x = x + u * cfg.dt
    return cfg, x, toward(goals, x, cfg.max_speed)


def test_budget_runs_out_at_the_same_count_and_the_floor_is_certified(jammed) -> None:
    cfg, x, nom = jammed
    exact, de = SafetyFilter(cfg).filter(x, nom)
    assert de.ok and de.work > 3 and not de.nominal_was_safe
    capped = dataclasses.replace(cfg, mode="anytime", work_budget=3)
    u1, d1 = SafetyFilter(capped).filter(x, nom)
    u2, d2 = SafetyFilter(capped).filter(x, nom)
    assert d1.ok and d1.answer == "floor" and d1.method == "distributed floor" and d1.gap is None
    assert d1.work == d2.work == 3 and np.array_equal(u1, u2)
    rows = barrier_rows(x, cfg)
    assert np.all(rows.lhs(u1) <= rows.b + 2e-10)
    assert np.all(np.einsum("kd,kd->k", u1, u1) <= cfg.max_speed**2)
    # more invasive than the optimum, never less
    assert np.sum((u1 - nom) ** 2) >= np.sum((exact - nom) ** 2)
    # a budget above what the exact solve needs gives the optimum itself
    ub, db = SafetyFilter(dataclasses.replace(cfg, mode="anytime", work_budget=de.work)).filter(x, nom)
    assert db.answer == "optimum" and np.array_equal(ub, exact)


def test_warm_cap_falls_back_to_clarabel_cold_with_the_optimum(jammed) -> None:
    cfg, x, nom = jammed
    plain = SafetyFilter(cfg)
    capped = SafetyFilter(dataclasses.replace(cfg, active_set_max_solves=1))
    fell_back = 0
    for _ in range(5):
        u, d = plain.filter(x, nom)
        uc, dc = capped.filter(x, nom)
        assert d.ok and dc.ok and dc.answer == "optimum"
        # polished: the exact optimum; the polish capped too: clarabel's own answer (rows to 1e-7 m/s)
        np.testing.assert_allclose(uc, u, rtol=0, atol=1e-9 if dc.method == "clarabel+active-set" else 1e-4)
        rows = barrier_rows(x, cfg)
        assert np.all(rows.lhs(uc) <= rows.b + 1e-7)
        fell_back += dc.method.startswith("clarabel")
        x = x + u * cfg.dt
    assert fell_back >= 1
