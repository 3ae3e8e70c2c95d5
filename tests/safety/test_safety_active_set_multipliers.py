"""The active set started from predicted rows *and* their multipliers (a dual ascent's).

Defect this guards: on the dense, degenerate scenes (more active rows than a cluster has relative
degrees of freedom) one wrongly predicted row made the active set drop every negative least-norm
multiplier at once — rows that belong too — and it never certified (N = 1000: 8 of 11 closed-loop
ticks fell back to clarabel). From dual-feasible multipliers, Lawson–Hanson steps drop the wrong
row first (its multiplier is the small one).
"""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.safety import BarrierConfig, SafetyFilter
from swarmdeck.safety.active_set import solve_active_set
from swarmdeck.safety.constraints import barrier_rows
from swarmdeck.safety.scenes import arena_for, grid_scene


# N = 200 scenes on which the start without multipliers does not certify within 4 iterations
@pytest.mark.parametrize("seed,extra", [(1, 1), (1, 3), (3, 3)])
def test_wrong_rows_with_small_multipliers_leave_first(seed: int, extra: int) -> None:
    cfg = BarrierConfig(bounds=arena_for(200, 0.188))
    x, nominal = grid_scene(200, np.random.default_rng(seed), cfg, pitch=0.188)
    rows = barrier_rows(x, cfg)
    cold, diag = SafetyFilter(cfg).filter(x, nominal)
    assert diag.ok
    exact = solve_active_set(rows, nominal, cfg.max_speed, rows.lhs(cold) > rows.b - 1e-9, 60)
    assert exact.ok
    slack = rows.b - rows.lhs(cold)
    slack[exact.active | (slack <= 1e-9)] = np.inf
    wrong = np.argsort(slack)[:extra]  # the inactive rows nearest their bound
    assert np.all(np.isfinite(slack[wrong]))
    predicted = exact.active.copy()
    predicted[wrong] = True
    lam = exact.multipliers.copy()
    lam[wrong] = 1e-6
    res = solve_active_set(rows, nominal, cfg.max_speed, predicted, 4, multipliers=lam)
    assert res.ok, res.reason
    assert res.iterations <= 2
    np.testing.assert_allclose(res.u, cold, rtol=0, atol=1e-12)
    assert not np.any(res.active[wrong])
