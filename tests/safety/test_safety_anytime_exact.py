"""Anytime barrier (issue 27 item 1): with an unlimited budget it is today's centralised filter, bit for bit.

``mode="anytime"`` with ``work_budget=None`` (and no warm cap) never computes the floor: every
tick of a closed loop over the dense crossing equals the centralised filter's answer exactly,
says ``answer == "optimum"`` with ``gap == 0``; ``mode="auto"`` at N ≤ ``distributed_above``
is the same.
"""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from swarmdeck.safety import SafetyFilter
from swarmdeck.safety.scenes import crossing_scene, toward


@pytest.mark.parametrize("n", [30, 120])
def test_unlimited_anytime_is_the_centralised_optimum(n: int) -> None:
    cfg, x, goals = crossing_scene(n, np.random.default_rng(n))
    central = SafetyFilter(dataclasses.replace(cfg, mode="centralised"))
    anytime = SafetyFilter(dataclasses.replace(cfg, mode="anytime"))
    auto = SafetyFilter(dataclasses.replace(cfg, mode="auto", distributed_above=n))
    intervened = 0
    for _ in range(40):
        nom = toward(goals, x, cfg.max_speed)
        u, d = central.filter(x, nom)
        ua, da = anytime.filter(x, nom)
        uo, do = auto.filter(x, nom)
        assert d.ok and da.ok and do.ok
        assert np.array_equal(u, ua) and np.array_equal(u, uo)
        assert da.answer == do.answer == "optimum" and da.gap == 0.0 and da.method == d.method
        intervened += not d.nominal_was_safe
        x = x + u * cfg.dt
    assert intervened > 10  # the crossing makes the filter work
