"""Virtual robots beside physical ones: the MQTT fleet (a `swarmdeck robots` FleetNode on a real mosquitto
broker) as the physical robots and robots simulated in the console's process, driven by one loop to a
rendezvous: they meet, and no physical robot ever collides with a virtual one (nor any two robots)."""
from __future__ import annotations

import threading
import time

import numpy as np
import pytest
from mqtt_broker import wait_until

from swarmdeck.console.runtime.hardware import mqtt_robots
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.core.kinematics import lookahead_points
from swarmdeck.devices import ArenaConfig, colliding_pairs
from swarmdeck.devices.net.fleet import FleetNode
from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.virtual_robots import MixedRobots

pytestmark = pytest.mark.mqtt


def _cross_distance(frame) -> float:
    """Smallest look-ahead distance between a physical and a virtual robot of one Frame, m."""
    p = lookahead_points(frame.poses, frame.lookahead)
    v = frame.is_virtual
    return float(np.linalg.norm(p[~v][:, None, :] - p[v][None, :, :], axis=2).min())


def test_physical_and_virtual_robots_meet_without_collisions(mosquitto):
    # physical robots on the left half, so the virtual ones (placed clear of them) start elsewhere
    physical = np.array([[-1.2, -0.5, 0.0], [-1.2, 0.5, 0.0], [-0.6, 0.0, 0.0], [-0.6, -0.7, 1.0]])
    fleet = FleetNode(parse_broker_url(mosquitto.url), [0, 1, 2, 3], physical, name="fleet-physical").start()
    loop = None
    frames = []
    lock = threading.Lock()

    def keep(frame):
        with lock:
            frames.append(frame)

    try:
        sink, source = mqtt_robots(mosquitto.url, np.arange(4), wait_for_poses=15)
        mixed = MixedRobots.add_virtual(source, sink, 5, ArenaConfig(seed=4))
        loop = ControlLoop(LoopConfig(n_robots=4, behaviour="rendezvous"), source=mixed, sink=mixed,
                           clock=time.monotonic)
        loop.subscribe(keep)
        loop.start()
        # they meet: some physical robot comes within 0.25 m of a virtual one (the barrier holds D_s = 0.17 m)
        wait_until(lambda: loop.latest is not None and loop.latest.seen.all() and _cross_distance(loop.latest) < 0.25,
                   60, "a physical and a virtual robot meeting")
        loop.stop()
    finally:
        if loop is not None:
            loop.close()
        fleet.stop()
    with lock:
        seen = [f for f in frames if f.seen.all()]
    assert len(seen) > 10
    for f in seen:
        assert f.n == 9 and f.is_virtual.tolist() == [False] * 4 + [True] * 5
        assert f.ids.tolist() == list(range(9))  # virtual ids follow the physical ones
        assert f.barrier is not None and f.barrier.ok
        assert len(colliding_pairs(f.poses)) == 0  # 0 collisions, between the kinds and within each
    # the barrier did act between the two kinds: some active pair joins a physical and a virtual robot
    mixed_pairs = [p for f in seen for p in f.barrier.active_pairs if f.is_virtual[p[0]] != f.is_virtual[p[1]]]
    assert mixed_pairs
    # the virtual robots really moved, and only in the console (the fleet knows nothing of ids 4..8)
    assert np.linalg.norm(seen[-1].poses[4:, :2] - seen[0].poses[4:, :2], axis=1).max() > 0.05
    assert fleet.snapshot()["ids"].tolist() == [0, 1, 2, 3]
