"""The distributed filter's certificate fails closed on NaN (a defect found in review, session 6): a row whose
excess is NaN — a NaN answer, or a NaN bound from a NaN pose — never compares greater than the tolerance, so the
old check ``worst > tol`` let it pass as certified. Both the numpy path (≤ 12 robots) and the compiled one now
report the first NaN row as the worst, and ``filter_distributed`` refuses the answer (the robots stop)."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from swarmdeck.safety import BarrierConfig, distributed
from swarmdeck.safety.constraints import Rows, barrier_rows
from swarmdeck.safety.scenes import arena_for, grid_scene


def _jammed(n: int, seed: int) -> tuple[BarrierConfig, np.ndarray, Rows]:
    """(config, nominal (n, 2) m/s, the barrier's rows) of a jammed grid of ``n`` robots."""
    cfg = BarrierConfig(bounds=arena_for(n, 0.188, fill=0.9))
    x, nominal = grid_scene(n, np.random.default_rng(seed), cfg, pitch=0.188)
    return cfg, nominal, barrier_rows(x, cfg)


@pytest.mark.parametrize("n", [8, 60])  # the numpy path, the compiled one
def test_a_nan_row_is_the_worst_row(n: int) -> None:
    _, _, rows = _jammed(n, seed=1)
    b = rows.b.copy()
    b[rows.m // 2] = np.nan
    worst, k = distributed._worst_row(rows, np.zeros((n, 2)), b)
    assert np.isnan(worst) and k == rows.m // 2, (worst, k)
    u = np.zeros((n, 2))
    u[3] = np.nan
    worst, k = distributed._worst_row(rows, u, rows.b)
    assert np.isnan(worst) and k == int(np.flatnonzero(np.isnan(rows.lhs(u)))[0]), (worst, k)


@pytest.mark.parametrize("n", [8, 60])
def test_the_filter_refuses_an_answer_it_cannot_certify(n: int) -> None:
    cfg, nominal, rows = _jammed(n, seed=2)
    b = rows.b.copy()
    b[rows.j >= 0] = np.where(np.arange(int(np.sum(rows.j >= 0))) == 0, np.nan, b[rows.j >= 0])
    out = distributed.filter_distributed(dataclasses.replace(rows, b=b), nominal, cfg.max_speed, cfg)
    assert not out.ok and np.array_equal(out.u, np.zeros((n, 2))), out.reason
