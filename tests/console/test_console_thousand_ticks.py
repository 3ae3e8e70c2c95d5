"""The console loop at N = 1000 over 1000 ticks on a virtual clock: no collision, every frame complete.

1000 robots in a 16 × 10 m arena, each driving to a random place of the go-to goal grid (the
swarm crosses through itself; the barrier changes most robots' commands on every tick), filtered
by the console's default barrier ("auto": distributed above 200 robots). The behaviour is the
cheap go-to controller rather than coverage so that 1000 ticks of 1000 robots fit in the test's
time (≈ 10 ms of CPU a tick against ≈ 30 ms with coverage); coverage at N = 1000 in the 10 × 6 m
arena is ``test_console_thousand.py``. Not 10 × 6 m here: its layout fills 87 % of the lattice
(median neighbour distance 0.21 m for D_s = 0.17 m), and a swarm that crosses itself there jams
(median travel 9 cm in 1000 ticks) — still safe, but the same configuration a thousand times.
"""
from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from swarmdeck.console.runtime.behaviours import default_goals
from swarmdeck.console.runtime.config import arena_bounds
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig

ARENA = arena_bounds("16x10")
N, TICKS = 1000, 1000


def test_a_thousand_robots_cross_the_arena_for_a_thousand_ticks_without_collision() -> None:
    loop = ControlLoop(LoopConfig(n_robots=N, seed=3, bounds=ARENA))
    goals = default_goals(N, ARENA)[np.random.default_rng(3).permutation(N)]
    loop.set_params(goals=tuple(map(tuple, goals.tolist())))
    loop.set_behaviour("goto")
    try:
        first = loop.tick()
        start = first.points.copy()
        closest, busy = np.inf, 0
        for k in range(1, TICKS):
            f = loop.tick()
            assert f.tick == first.tick + k and np.isclose(f.time - first.time, k * f.dt)  # virtual clock
            assert f.n == N and np.all(np.isfinite(f.poses)) and f.barrier is not None
            assert f.barrier.ok and f.barrier.status.startswith("optimal per robot"), f.barrier.status
            d = float(cKDTree(f.points).query(f.points, k=2)[0][:, 1].min())
            assert d >= f.barrier.safety_distance - 1e-6, (k, d)  # no collision: look-ahead points ≥ D_s apart
            x0, x1, y0, y1 = ARENA
            assert np.all((f.poses[:, 0] > x0) & (f.poses[:, 0] < x1) & (f.poses[:, 1] > y0) & (f.poses[:, 1] < y1))
            closest = min(closest, d)
            busy += int(np.any(f.barrier.intervention > 1e-3))
    finally:
        loop.close()
    assert busy > TICKS // 2  # the barrier really had to act on most ticks
    assert closest < f.barrier.safety_distance + 0.02  # and robots really came close
    travelled = np.linalg.norm(f.points - start, axis=1)
    assert np.median(travelled) > 0.5  # the swarm really moved (33 s of virtual time)
