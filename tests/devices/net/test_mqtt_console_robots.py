"""NetworkRobots: the console loop's pose source and command sink over a real broker; a silent robot
is excluded from control and becomes a fixed obstacle for the safety barrier."""
from __future__ import annotations

import numpy as np
import pytest
from mqtt_broker import wait_until

from swarmdeck.devices import lookahead_points, random_initial_poses, si_to_unicycle
from swarmdeck.devices.net.console_robots import NetworkRobots
from swarmdeck.devices.net.fleet import FleetNode
from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.net.transport_mqtt import LinkTimeouts
from swarmdeck.safety import BarrierConfig, SafetyFilter

pytestmark = pytest.mark.mqtt


def test_silent_robot_is_excluded_and_becomes_an_obstacle(mosquitto):
    cfg = parse_broker_url(mosquitto.url)
    poses = random_initial_poses(4, rng=21)
    main = FleetNode(cfg, [0, 1, 2], poses[:3], name="fleet-main").start()
    lone = FleetNode(cfg, [3], poses[3:], name="fleet-lone").start()
    robots = None
    try:
        robots = NetworkRobots.connect(mosquitto.url, n_robots=4, timeouts=LinkTimeouts(missing_after=0.6))
        sensed = wait_until(lambda: (s := robots.read()) and s.seen.all() and len(s.ids) == 4 and s, what="4 fresh poses")
        assert sensed.ids.tolist() == [0, 1, 2, 3]
        robots.send(sensed.ids, np.full(4, 0.05), np.zeros(4))
        wait_until(lambda: np.all(main.snapshot()["v"] == 0.05) and lone.snapshot()["v"][0] == 0.05, what="commands applied")
        assert robots.health().startswith("connected") and "4 ok" in robots.health()
        last3 = lone.snapshot()["poses"][0].copy()
        lone.stop()  # robot 3 goes silent (its fleet died)
        sensed = wait_until(lambda: (s := robots.read()) and len(s.ids) == 3 and s, what="robot 3 excluded")
        assert sensed.ids.tolist() == [0, 1, 2]
        obstacles = robots.obstacles()
        assert obstacles.shape == (1, 2) and np.allclose(obstacles[0], last3[:2], atol=0.02)
        assert "1 missing" in robots.health()
        assert robots.robot_health()["3"]["link"] == "missing"
        wait_until(lambda: any("[3]" in e and "excluded" in e for e in robots.events()), what="exclusion event")
        # the barrier keeps the others D_s away from the silent robot's last position
        points = lookahead_points(sensed.poses, 0.03)
        toward = obstacles[0] - points
        nominal = 0.2 * toward / np.linalg.norm(toward, axis=1, keepdims=True)
        safe, diag = SafetyFilter(BarrierConfig()).filter(points, nominal, obstacles=obstacles)
        assert diag.ok
        robots.send(sensed.ids, *si_to_unicycle(sensed.poses, safe, 0.03))
        tick = robots.streamer.last_tick
        assert tick.ids.tolist() == [0, 1, 2] and tick.delivered
    finally:
        if robots is not None:
            robots.close()
        main.stop()
        lone.stop()


def test_connect_names_the_missing_robots(mosquitto):
    with pytest.raises(ValueError, match=r"no pose from robot id\(s\) \[0, 1\]"):
        NetworkRobots.connect(mosquitto.url, n_robots=2, wait_for_poses=0.3)
