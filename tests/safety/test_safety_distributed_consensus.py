"""Distributed barrier, consensus shares (issue 27 item 1): a split of each pair's margin from a few
sweeps of dual ascent, still certified.

``BarrierConfig.distributed_consensus_sweeps = K > 0``: the second pass splits each pair row's margin
at an estimate ũ of the joint optimum (robot i's share ``c_iᵀũ_i + slack/2``), falling back pair by pair
to a split that keeps the first answer feasible where a robot's own QP would be infeasible. In closed
loop (adversarial nominals, N up to 300, line-segment obstacles across the floor) every centralised row
(pairs, walls, segments) and every speed bound holds and no two robots come closer than D_s.
"""
from __future__ import annotations

import dataclasses

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.distance import pdist
from test_safety_invariance import DT, MODES, adversarial

from swarmdeck.core.obstacles import Obstacles, point_segment_distance
from swarmdeck.safety import BarrierConfig, SafetyFilter
from swarmdeck.safety.constraints import barrier_rows
from swarmdeck.safety.scenes import arena_for, grid_scene


@settings(max_examples=6, deadline=None)
@given(n=st.integers(2, 300), sweeps=st.sampled_from([1, 2, 4, 8]), seed=st.integers(0, 2**32 - 1),
       walls=st.booleans())
def test_closed_loop_with_consensus_shares_keeps_every_row(n: int, sweeps: int, seed: int, walls: bool) -> None:
    rng = np.random.default_rng(seed)
    base = BarrierConfig(dt=DT, mode="distributed", distributed_consensus_sweeps=sweeps)
    pitch = base.safety_distance + 0.02
    bounds = arena_for(n, pitch, fill=0.6, margin=base.margin + 0.01)
    x0, x1, y0, y1 = bounds
    x, _ = grid_scene(n, rng, dataclasses.replace(base, bounds=bounds), pitch=pitch)
    segments = np.array([[[x0 + 0.2, 0.1 * y0], [0.0, 0.1 * y0]], [[0.3 * x1, 0.2 * y1], [x1 - 0.2, 0.2 * y1]]])
    clear = point_segment_distance(x, segments).min(axis=1) >= base.margin + 0.01
    walls = walls and int(clear.sum()) >= 2
    if walls:  # two segments across the floor; the robots on them at the start are taken away
        x = x[clear]
    cfg = dataclasses.replace(base, bounds=bounds, obstacles=Obstacles(segments) if walls else None)
    f = SafetyFilter(cfg)
    target = rng.permutation(x.shape[0])
    mode = MODES[seed % len(MODES)]
    for k in range(25):
        if k % 10 == 0:
            mode, target = MODES[rng.integers(len(MODES))], rng.permutation(x.shape[0])
        nom = adversarial(mode, x, rng, target, cfg.max_speed)
        u, diag = f.filter(x, nom)
        assert diag.ok and diag.method == "distributed", diag.status
        rows = barrier_rows(x, cfg)
        assert np.all(rows.lhs(u) <= rows.b + 1e-9), "a centralised row is violated by the consensus shares"
        assert np.all(np.linalg.norm(u, axis=1) <= cfg.max_speed * (1 + 1e-9))
        x = x + u * DT
        if x.shape[0] >= 2:
            assert pdist(x).min() >= cfg.safety_distance - 1e-7
