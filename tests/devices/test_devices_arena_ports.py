"""One robot vocabulary: the Arena drives robot ports (core/ports.py) through one adapter, SteppedRobots.

The simulation, networked robots (here over the in-process transport: MQTT is the same class over
MqttTransport), virtual robots beside them, a fleet's assigned robots and the sandboxed script's
robots are all pose source + command sink; ``Arena`` wraps whichever it gets in
``devices.stepped.SteppedRobots`` and nothing else. The classes the ports replaced are gone.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from swarmdeck.core.ports import CommandSink, PoseSource
from swarmdeck.devices import Arena, ArenaConfig, SimulatedArena
from swarmdeck.devices.net.console_robots import NetworkRobots
from swarmdeck.devices.net.transport_inprocess import InProcessTransport
from swarmdeck.devices.stepped import SteppedRobots

ROOT = Path(__file__).resolve().parents[2]


def classes() -> dict[str, list[str]]:
    found: dict[str, list[str]] = {}
    for path in ROOT.rglob("*.py"):
        rel = path.relative_to(ROOT).as_posix()
        if rel.startswith((".venv/", "tests/", "build/")):
            continue
        for name in re.findall(r"^class (\w+)\b", path.read_text(encoding="utf-8"), flags=re.M):
            found.setdefault(name, []).append(rel)
    return found


def test_the_arena_runs_over_the_ports_through_one_adapter() -> None:
    found = classes()
    for gone in ("RobotBackend", "TransportBackend", "MixedBackend"):
        assert gone not in found, (gone, found[gone])
    assert found["SteppedRobots"] == ["devices/stepped.py"]
    arena = Arena(3, config=ArenaConfig(seed=1))
    assert isinstance(arena.backend, PoseSource) and isinstance(arena.backend, CommandSink)
    assert type(arena.robots) is SteppedRobots and arena.robots.simulated


def networked(n: int, seed: int) -> tuple[NetworkRobots, InProcessTransport]:
    transport = InProcessTransport(SimulatedArena(n, config=ArenaConfig(seed=seed)))
    robots = NetworkRobots(transport, np.arange(n), background=False, clock=lambda: transport.time,
                           simulated_time=True)
    return robots, transport


def test_an_arena_with_its_barrier_drives_networked_robots_as_it_drives_the_simulation() -> None:
    # Before: an Arena over the transport's robots with the barrier on handed the barrier their
    # obstacles *method* as the obstacle array and failed on its first step.
    n, seed = 6, 8
    direct = Arena(n, config=ArenaConfig(seed=seed))
    robots, transport = networked(n, seed)
    via = Arena(backend=robots, config=ArenaConfig(seed=seed))
    assert np.array_equal(direct.poses(), via.poses())
    goal = np.array([0.0, 0.0])  # everybody to the centre: the barrier must hold them apart
    for _ in range(300):
        for arena in (direct, via):
            p = arena.positions()
            arena.set_velocities(np.clip(goal - p, -0.15, 0.15))
            arena.step()
    assert np.array_equal(direct.poses(), via.poses())
    assert direct.time == via.time and via.safety_stats.failures == 0
    assert via.safety_stats.interventions == direct.safety_stats.interventions > 0
    assert transport.status().counters["commands_sent"] == 300 * n
    robots.close()


def test_robots_missing_from_a_reading_keep_their_last_pose() -> None:
    robots, transport = networked(3, 2)
    arena = Arena(backend=robots, config=ArenaConfig(seed=2), safety=False)
    before = arena.poses()
    robots.ids = np.array([0, 2])  # robot 1 left out of control (as an excluded robot is)
    after = arena.poses()
    np.testing.assert_array_equal(after, before)
    assert arena.n == 3 and arena.robots.ids.tolist() == [0, 1, 2]
    robots.close()
