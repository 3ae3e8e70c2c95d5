"""The falsifier's fixture (examples/near_miss.py) evaluated in this process: the same trusted plant verification
uses — the simulator under :class:`~swarmdeck.console.sandbox.plant.VerificationRobots` (tracking noise, latency,
drops, the contact model) driven with the script's open-loop commands (no barrier: a raw run),
without the jail (a run takes milliseconds instead of a sandboxed run's half second). Imported by
tests/sandbox/test_sandbox_falsify_search.py and bench/bench_falsify.py."""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.sandbox.falsify import SearchSpace
from swarmdeck.console.sandbox.plant import Disturbances, VerificationRobots
from swarmdeck.devices.simulator import ArenaConfig, SimulatedArena

#: examples/near_miss.py's start poses (m, rad), speed (m/s) and a duration past the pass (s: they pass at 1.7 s)
NEAR_MISS_START = np.array([[-0.3, 0.0, 0.0], [0.3, 0.185, np.pi]])
NEAR_MISS_SPEED = 0.18
NEAR_MISS_DURATION = 2.2
NEAR_MISS_SPACE = SearchSpace.within_noise(2, Disturbances().pose_noise_xy, Disturbances().pose_noise_theta)


def near_miss_run(z: NDArray[np.float64], seed: int = 0) -> float:
    """The minimum clearance (m, 0 at a contact) of one run of the fixture from candidate ``z`` ``(12,)``."""
    probe = NEAR_MISS_SPACE.decode(z)
    poses = NEAR_MISS_START + np.array(probe.setup)
    config = ArenaConfig(seed=None)
    sim = SimulatedArena(2, poses, config=config)
    robots = VerificationRobots(sim, Disturbances(), np.random.default_rng(seed), contact_distance=sim.params.diameter,
                                offset=np.array(probe.offset))
    v, w = np.full(2, NEAR_MISS_SPEED), np.zeros(2)
    for _ in range(int(round(NEAR_MISS_DURATION / config.dt))):
        robots.step(v, w)  # what the Arena sends for the script's set_unicycle (no barrier: raw)
    if robots.contacts.contacts:  # touched: nothing is closer (non-penetration stops them at the contact)
        return 0.0
    return max(0.0, float(robots.closest.clearance))


def near_miss_objective(candidates: NDArray[np.float64]) -> NDArray[np.float64]:
    """:func:`near_miss_run` of every row of ``candidates`` ``(P, 12)`` (a batch objective of the search)."""
    return np.array([near_miss_run(z) for z in candidates])
