"""A cold call (issue 27 item 1, cold N = 100 ≤ 2 ms): the dual prediction from zero certifies before clarabel.

``BarrierConfig.cold_dual`` (on by default): with no warm start, when the active set from the
rows û violates does not apply, the compiled dual ascent from zero multipliers predicts the
active rows and the active set certifies the exact optimum from them (KKT, every row, every
speed bound); clarabel runs only when that fails. On the random dense scenes of the benches the
answer is the one clarabel + its polish gives, to the last bit here (the certified active set's
solve from the optimum's own active rows), at a fraction of the work.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from swarmdeck.safety import BarrierConfig, SafetyFilter
from swarmdeck.safety import filter as filter_module
from swarmdeck.safety.constraints import barrier_rows
from swarmdeck.safety.scenes import grid_scene


def test_cold_calls_certify_without_clarabel_and_keep_the_answer(monkeypatch) -> None:
    cfg = BarrierConfig()
    rng = np.random.default_rng(1)
    clarabel_calls = []
    real_qp = filter_module.solve_qp

    def spy_qp(*args, **kwargs):
        clarabel_calls.append(1)
        return real_qp(*args, **kwargs)

    for _ in range(3):
        x, nom = grid_scene(100, rng, cfg, pitch=0.188)
        before, db = SafetyFilter(dataclasses.replace(cfg, cold_dual=False)).filter(x, nom)
        assert db.ok and db.method == "clarabel+active-set", db.method
        monkeypatch.setattr(filter_module, "solve_qp", spy_qp)
        u, d = SafetyFilter(cfg).filter(x, nom)
        monkeypatch.setattr(filter_module, "solve_qp", real_qp)
        assert d.ok and d.answer == "optimum" and d.method == "dual+active-set", d.method
        assert not clarabel_calls
        np.testing.assert_allclose(u, before, rtol=0, atol=1e-12)
        rows = barrier_rows(x, cfg)
        assert np.all(rows.lhs(u) <= rows.b + 1e-10)
        assert np.all(np.einsum("kd,kd->k", u, u) <= cfg.max_speed**2)


def test_cold_dual_is_a_validated_setting() -> None:
    assert BarrierConfig().cold_dual is True
    assert BarrierConfig.from_dict({"cold_dual": False}).cold_dual is False
    try:
        BarrierConfig(cold_dual=1)  # type: ignore[arg-type]
    except ValueError as exc:
        assert "cold_dual" in str(exc)
    else:
        raise AssertionError("cold_dual=1 was accepted")
