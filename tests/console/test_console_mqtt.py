"""The console loop driving a simulated GRITSBot fleet over a real mosquitto broker (--robots-via)."""
from __future__ import annotations

import time

import numpy as np
import pytest
from mqtt_broker import wait_until

from swarmdeck.console.runtime.hardware import mqtt_robots
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.devices import random_initial_poses
from swarmdeck.devices.net.fleet import FleetNode
from swarmdeck.devices.net.mqtt_config import parse_broker_url

pytestmark = pytest.mark.mqtt


def test_loop_drives_fleet_and_estop_zeroes_it(mosquitto):
    poses = random_initial_poses(4, rng=5)
    fleet = FleetNode(parse_broker_url(mosquitto.url), [0, 1, 2, 3], poses, name="fleet").start()
    loop = None
    try:
        sink, source = mqtt_robots(mosquitto.url, np.arange(4))
        loop = ControlLoop(LoopConfig(n_robots=4, behaviour="rendezvous"), source=source, sink=sink,
                           clock=time.monotonic)
        loop.start()
        wait_until(lambda: loop.latest is not None and loop.latest.seen.all(), what="fresh poses in the loop")
        wait_until(lambda: np.abs(fleet.snapshot()["v"]).max() > 0.01, what="robots commanded")
        wait_until(lambda: np.linalg.norm(fleet.snapshot()["poses"][:, :2] - poses[:, :2], axis=1).max() > 0.01,
                   what="robots moved")
        assert "connected" in loop.latest.health["robots"]
        loop.estop()
        wait_until(lambda: loop.latest.run_state == "estop", what="e-stop in a frame")
        wait_until(lambda: np.all(fleet.snapshot()["v"] == 0.0) and np.all(fleet.snapshot()["w"] == 0.0),
                   what="fleet zeroed")
        assert loop.latest.stopped
    finally:
        if loop is not None:
            loop.close()
        fleet.stop()


def test_no_robots_on_the_broker_is_a_clear_error(mosquitto):
    with pytest.raises(ValueError, match="no pose from robot id"):
        mqtt_robots(mosquitto.url, np.arange(2), wait_for_poses=0.3)
