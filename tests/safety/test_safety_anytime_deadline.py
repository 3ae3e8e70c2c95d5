"""Anytime barrier (issue 27 item 1): a wall-time budget that has already passed answers with the floor.

``time_budget_s`` is for the live console; tests never depend on timing, so this one uses a budget
(1 ns) that has always passed by the time the rows are built: the centralised QP gets no work at all
and the certified distributed floor answers.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from swarmdeck.safety import SafetyFilter
from swarmdeck.safety.constraints import barrier_rows
from swarmdeck.safety.scenes import crossing_scene, toward


def test_passed_deadline_gives_the_certified_floor() -> None:
    cfg, x, goals = crossing_scene(60, np.random.default_rng(3))
    cfg = dataclasses.replace(cfg, mode="anytime", time_budget_s=1e-9)
    # robots 0 and 1 head straight at each other, so the nominal is not safe
    x = x.copy()
    x[1] = x[0] + np.array([cfg.safety_distance + 0.01, 0.0])
    nom = toward(goals, x, cfg.max_speed)
    nom[0], nom[1] = (cfg.max_speed, 0.0), (-cfg.max_speed, 0.0)
    u, diag = SafetyFilter(cfg).filter(x, nom)
    assert diag.ok and diag.answer == "floor" and diag.work == 0, diag.status
    rows = barrier_rows(x, cfg)
    assert np.all(rows.lhs(u) <= rows.b + 2e-10)
    assert np.all(np.einsum("kd,kd->k", u, u) <= cfg.max_speed**2)
