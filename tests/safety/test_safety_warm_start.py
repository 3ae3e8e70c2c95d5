"""Closed-loop warm start (issue 18, item 1): answers identical (≤ 1e-9) to cold solves.

The filter keeps the previous tick's active rows and multipliers. By default the compiled dual
coordinate ascent (``safety.dual_ascent``) started from those multipliers predicts the active rows
and the certified active set starts from them; without it (``warm_dual_sweeps=0``, or no numba)
the active set starts from last tick's active rows (up to ``BarrierConfig.warm_max_rows`` rows),
beyond that clarabel solves the rows near their bound. Every warm answer is still certified (KKT,
every row, speed bound) and must equal a fresh filter's answer on the same points and nominal.
"""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.safety import BarrierConfig, SafetyFilter
from swarmdeck.safety.constraints import barrier_rows
from swarmdeck.safety.scenes import arena_for, grid_scene

DUAL = "warm dual+active-set"


def closed_loop_methods(n: int, ticks: int, cfg: BarrierConfig) -> list[str]:
    """Run one filter over a closed loop, checking every tick against a fresh filter; its methods."""
    rng = np.random.default_rng(n)
    x, nominal = grid_scene(n, rng, cfg, pitch=0.188)
    ang = np.arctan2(nominal[:, 1], nominal[:, 0])
    speed = np.linalg.norm(nominal, axis=1)
    warm = SafetyFilter(cfg)
    methods = []
    for _ in range(ticks):
        nom = np.stack([np.cos(ang), np.sin(ang)], axis=1) * speed[:, None]
        u, diag = warm.filter(x, nom)
        cold, cdiag = SafetyFilter(cfg).filter(x, nom)
        assert diag.ok and cdiag.ok, (diag.status, cdiag.status)
        np.testing.assert_allclose(u, cold, rtol=0, atol=1e-9)
        rows = barrier_rows(x, cfg)
        assert np.all(rows.lhs(u) <= rows.b + 1e-9)
        assert np.all(np.einsum("kd,kd->k", u, u) <= cfg.max_speed**2)
        methods.append(diag.method)
        x = x + u * cfg.dt
        ang = ang + rng.normal(0, 0.1, n)
    return methods


def config(n: int, **kw) -> BarrierConfig:
    return BarrierConfig(**kw) if n <= 100 else BarrierConfig(bounds=arena_for(n, 0.188), **kw)


@pytest.mark.parametrize("n,ticks,path", [(30, 25, "warm active-set"), (100, 12, "warm active-set"),
                                          (300, 8, "warm clarabel+active-set")])
def test_uncompiled_warm_answers_equal_cold_solves(n: int, ticks: int, path: str) -> None:
    """Without the dual-ascent prediction: N ≤ 100 the active set from last tick's active rows;
    N = 300 (≈ 800 active rows, beyond ``warm_max_rows``): clarabel on the rows near their bound
    last tick, finished on all rows."""
    methods = closed_loop_methods(n, ticks, config(n, warm_dual_sweeps=0))
    assert methods.count(path) >= ticks // 2, methods  # the warm start is really used


@pytest.mark.parametrize("n,ticks", [(30, 25), (100, 12), (300, 8)])
def test_dual_ascent_warm_answers_equal_cold_solves(n: int, ticks: int) -> None:
    methods = closed_loop_methods(n, ticks, config(n))
    assert methods.count(DUAL) >= ticks // 2, methods


def test_a_failed_prediction_falls_back_to_the_other_paths() -> None:
    """One sweep and one active-set iteration cannot certify these ticks: the filter goes on to
    the uncompiled warm paths, and the answers are still the cold ones."""
    methods = closed_loop_methods(100, 6, config(100, warm_dual_sweeps=1, warm_dual_iterations=1))
    assert "warm active-set" in methods, methods


def test_warm_start_forgotten_when_the_robots_change() -> None:
    cfg = BarrierConfig()
    x, nominal = grid_scene(40, np.random.default_rng(1), cfg, pitch=0.188)
    f = SafetyFilter(cfg)
    f.filter(x, nominal)
    u, diag = f.filter(x[:30], nominal[:30])  # other robots: no warm start from the 40
    cold, _ = SafetyFilter(cfg).filter(x[:30], nominal[:30])
    assert diag.ok and diag.method not in ("warm active-set", DUAL)
    np.testing.assert_allclose(u, cold, rtol=0, atol=1e-9)


@pytest.mark.parametrize("n,ticks", [(100, 8), (300, 5)])
def test_a_second_call_on_the_same_tick_reproduces_the_answer_to_the_bit(n: int, ticks: int) -> None:
    """The console and the arena pipeline filter the same tick with filters of different warm
    histories and must agree exactly: the answer cannot depend on which rows the prediction held."""
    cfg = config(n)
    rng = np.random.default_rng(n + 1)
    x, nominal = grid_scene(n, rng, cfg, pitch=0.188)
    f = SafetyFilter(cfg)
    for _ in range(ticks):
        u, diag = f.filter(x, nominal)
        again, diag2 = f.filter(x, nominal)
        assert diag.ok and diag2.ok
        np.testing.assert_array_equal(again, u)
        x = x + u * cfg.dt
        nominal = nominal + rng.normal(0, 0.01, nominal.shape)
