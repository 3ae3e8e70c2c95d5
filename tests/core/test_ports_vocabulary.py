"""One robot-port vocabulary: every robot kind speaks core.ports' PoseSource / CommandSink / SensedPoses.

The simulator, the overhead camera (tracking) and networked robots over a transport (here the
in-process one; MQTT is the same class over MqttTransport) give the control loop the same reading
type through the same protocols, and each concept is defined once in the source tree.
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from swarmdeck.core.ports import CommandSink, PoseSource, SensedPoses
from swarmdeck.devices import ArenaConfig, SimulatedArena
from swarmdeck.devices.net.console_robots import NetworkRobots
from swarmdeck.devices.net.streamer import StreamerConfig
from swarmdeck.devices.net.transport_inprocess import InProcessTransport
from swarmdeck.devices.simulated_robots import SimulatedRobots

ROOT = Path(__file__).resolve().parents[2]


def check_reading(r: SensedPoses, n: int) -> None:
    assert type(r) is SensedPoses
    assert r.ids.shape == (n,) and r.poses.shape == (n, 3) and r.seen.shape == (n,)


def test_the_simulator_is_both_ports() -> None:
    sim = SimulatedRobots(3, ArenaConfig(seed=1))
    assert isinstance(sim, PoseSource) and isinstance(sim, CommandSink)
    check_reading(sim.read(0.0), 3)


def test_the_camera_is_a_pose_source() -> None:
    from swarmdeck.console.runtime.hardware import camera_source

    sim = SimulatedRobots(3, ArenaConfig(seed=1))
    cam = camera_source("synthetic", np.arange(3), lambda now: sim.read(now).poses, (-1.6, 1.6, -1.0, 1.0))
    try:
        assert isinstance(cam, PoseSource) and not isinstance(cam, CommandSink)
        r = cam.read(0.0)
        check_reading(r, 3)
        assert r.seen.all()
        np.testing.assert_allclose(r.poses[:, :2], sim.read(0.0).poses[:, :2], atol=0.02)
    finally:
        cam.close()


def test_networked_robots_over_a_transport_are_both_ports() -> None:
    transport = InProcessTransport(SimulatedArena(4, config=ArenaConfig(seed=2)))
    robots = NetworkRobots(transport, background=False, clock=lambda: transport.time,
                           streamer=StreamerConfig(period=0.033))
    try:
        assert isinstance(robots, PoseSource) and isinstance(robots, CommandSink)
        r = robots.read(0.0)
        check_reading(r, 4)
        np.testing.assert_array_equal(r.poses, transport.arena.poses)
    finally:
        robots.close()


def test_each_port_concept_is_defined_once() -> None:
    found: dict[str, list[str]] = {}
    for path in ROOT.rglob("*.py"):
        rel = path.relative_to(ROOT).as_posix()
        if rel.startswith((".venv/", "tests/", "build/")):
            continue
        for name in re.findall(r"^class (\w+)\b", path.read_text(encoding="utf-8"), flags=re.M):
            found.setdefault(name, []).append(rel)
    for concept in ("SensedPoses", "PoseSource", "CommandSink"):
        assert found.get(concept) == ["core/ports.py"], (concept, found.get(concept))
    for gone in ("SensedRobots", "TransportSink"):
        assert gone not in found, (gone, found[gone])
