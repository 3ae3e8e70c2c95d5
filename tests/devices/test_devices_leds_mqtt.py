"""LEDs an experiment sets reach robots that have them (issue 28.1): ``Arena.set_leds`` on GRITSBots over MQTT (a
`swarmdeck robots` FleetNode on a real mosquitto broker) sends the colours with the commands, both LEDs of each
robot; the Arena's readings show them at once."""
from __future__ import annotations

import numpy as np
import pytest
from mqtt_broker import wait_until

from swarmdeck.core.ports import ShowsLeds
from swarmdeck.devices import Arena
from swarmdeck.devices.net.console_robots import NetworkRobots
from swarmdeck.devices.net.fleet import FleetNode
from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.sensing import SensingConfig

pytestmark = pytest.mark.mqtt


def test_leds_set_in_an_arena_reach_the_robots(mosquitto):
    poses = np.array([[-0.5, 0.0, 0.0], [0.5, 0.0, np.pi]])
    fleet = FleetNode(parse_broker_url(mosquitto.url), [0, 1], poses, name="fleet-leds").start()
    robots = None
    try:
        robots = NetworkRobots.connect(mosquitto.url, ids=[0, 1], wait_for_poses=15)
        assert isinstance(robots, ShowsLeds)
        arena = Arena(backend=robots, sensing=SensingConfig(), safety=False)
        arena.set_leds(np.array([[255, 0, 0], [0, 0, 255]]))
        assert arena.sense().leds.tolist() == [[255, 0, 0], [0, 0, 255]]

        def shown() -> bool:
            arena.step()
            return fleet.state.leds[:, 0].tolist() == [[255, 0, 0], [0, 0, 255]]

        wait_until(shown, 30, "the LED colours at the robots")
        assert fleet.state.leds[:, 1].tolist() == [[255, 0, 0], [0, 0, 255]]  # both LEDs of each robot
    finally:
        if robots is not None:
            robots.close()
        fleet.stop()
