"""The compiled dual coordinate ascent that predicts the active rows (``safety.dual_ascent``).

Closed form: two robots driving head-on at each other; invariant: every sweep increases the dual
function g(λ) = ½‖u(λ) − û‖² + λᵀ(A u(λ) − b), u(λ) = Π_D(û − Aᵀλ), whose maximum is the QP's
optimum (so a prediction never comes from a worse dual point than last tick's multipliers).
"""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.safety import BarrierConfig, dual_ascent
from swarmdeck.safety.active_set import solve_active_set
from swarmdeck.safety.constraints import barrier_rows
from swarmdeck.safety.scenes import grid_scene


def dual_value(rows, nominal, vmax, lam) -> float:
    w = nominal.copy()
    np.subtract.at(w, rows.i, lam[:, None] * rows.ci)
    np.subtract.at(w, rows.jj, lam[:, None] * rows.cj)
    norm = np.linalg.norm(w, axis=1)
    u = np.where((norm > vmax)[:, None], w * (vmax / np.maximum(norm, 1e-300))[:, None], w)
    return float(0.5 * np.sum((u - nominal) ** 2) + lam @ (rows.lhs(u) - rows.b))


def test_head_on_pair_converges_to_the_closed_form() -> None:
    """Two robots 0.25 m apart on the x axis driving at each other at 0.1 m/s: the pair row
    n·(u_j − u_i) ≤ b is the only one; the optimum slows both symmetrically to −(b/2) each."""
    cfg = BarrierConfig()
    x = np.array([[-0.125, 0.0], [0.125, 0.0]])
    nominal = np.array([[0.1, 0.0], [-0.1, 0.0]])
    rows = barrier_rows(x, cfg)
    pair = rows.select(rows.j >= 0)
    b = float(pair.b[0])
    assert b < 0.2  # the nominal closing speed violates the row
    res = dual_ascent.ascend(pair, nominal, cfg.max_speed, np.zeros(1), 200, tol=1e-13)
    expect = np.array([[b / 2, 0.0], [-b / 2, 0.0]])
    np.testing.assert_allclose(res.u, expect, rtol=0, atol=1e-12)
    assert res.predicted.tolist() == [True]
    np.testing.assert_allclose(res.lam, [(0.2 - b) / 2], rtol=0, atol=1e-12)  # ‖a‖² = 2


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), n=st.integers(2, 60), sweeps=st.integers(1, 30))
def test_sweeps_never_decrease_the_dual_function(seed: int, n: int, sweeps: int) -> None:
    cfg = BarrierConfig()
    rng = np.random.default_rng(seed)
    x, nominal = grid_scene(n, rng, cfg, pitch=0.188)
    rows = barrier_rows(x, cfg)
    lam0 = np.where(rng.random(rows.m) < 0.3, rng.uniform(0, 0.05, rows.m), 0.0)
    g0 = dual_value(rows, nominal, cfg.max_speed, lam0)
    res = dual_ascent.ascend(rows, nominal, cfg.max_speed, lam0, sweeps)
    assert np.all(res.lam >= 0)
    assert dual_value(rows, nominal, cfg.max_speed, res.lam) >= g0 - 1e-12
    assert np.all(np.linalg.norm(res.u, axis=1) <= cfg.max_speed * (1 + 1e-12))


def test_converged_prediction_is_the_exact_active_set() -> None:
    """Run to convergence on a dense scene: the predicted rows start the active set, which
    certifies in one iteration and holds exactly the rows the cold active set holds."""
    cfg = BarrierConfig()
    x, nominal = grid_scene(60, np.random.default_rng(7), cfg, pitch=0.188)
    rows = barrier_rows(x, cfg)
    res = dual_ascent.ascend(rows, nominal, cfg.max_speed, np.zeros(rows.m), 20000, tol=1e-11)
    assert res.residual <= 1e-11
    warm = solve_active_set(rows, nominal, cfg.max_speed, res.predicted, 2)
    cold = solve_active_set(rows, nominal, cfg.max_speed, None, 60)
    assert warm.ok and cold.ok
    assert warm.iterations == 1
    np.testing.assert_allclose(warm.u, cold.u, rtol=0, atol=1e-12)
    np.testing.assert_allclose(res.u, cold.u, rtol=0, atol=1e-8)
