"""``Arena`` over a robot transport with its barrier on (the default): the backend's excluded robots reach the
barrier as fixed points (``core.ports.obstacles_of``), and the run matches the direct simulation bit for bit.

Before, ``Arena.step`` handed the backend's ``obstacles`` *method* to ``certify`` as if it were the points, and
the first step with the barrier on raised TypeError.
"""
from __future__ import annotations

import numpy as np

from swarmdeck.devices import Arena, ArenaConfig, SimulatedArena
from swarmdeck.devices.net.transport_backend import TransportBackend
from swarmdeck.devices.net.transport_inprocess import InProcessTransport


def test_arena_over_a_transport_with_the_barrier_matches_the_direct_simulation() -> None:
    n, seed = 5, 8
    direct = Arena(n, config=ArenaConfig(seed=seed))
    transport = InProcessTransport(SimulatedArena(n, config=ArenaConfig(seed=seed)))
    backend = TransportBackend(transport, np.arange(n), clock=lambda: transport.time, real_time=False,
                               wait_for_poses=0)
    via = Arena(backend=backend, config=ArenaConfig(seed=seed))
    assert via.safety is not None and direct.safety is not None
    goals = np.random.default_rng(3).uniform([-1.2, -0.7], [1.2, 0.7], (n, 2))
    for arena in (direct, via):
        arena.set_goals(goals, controller="clf")
    for _ in range(60):
        direct.step()
        via.step()
    assert np.array_equal(direct.poses(), via.poses())
    assert via.safety_stats.failures == 0
