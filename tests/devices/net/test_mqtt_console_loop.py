"""The console's control loop drives a `swarmdeck robots` process over a real broker: it covers, stays safe,
and the robots stop when the console stops."""
from __future__ import annotations

import subprocess
import sys
import time

import numpy as np
import pytest
from mqtt_broker import wait_until

from swarmdeck.console.runtime.hardware import mqtt_robots
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.devices import colliding_pairs
from swarmdeck.devices.clock import RealTimePacer
from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.net.transport_mqtt import MqttTransport

pytestmark = pytest.mark.mqtt


def test_console_loop_covers_safely_over_mqtt(mosquitto):
    n = 6
    fleet = subprocess.Popen(
        [sys.executable, "-c", "import sys; from swarmdeck.console.cli import main; sys.exit(main())", "robots",
         "--broker", mosquitto.url, "--robots", str(n), "--seed", "9", "--quiet"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    robots = None
    try:
        robots, source = mqtt_robots(mosquitto.url, np.arange(n), wait_for_poses=15)  # the --robots-via path
        loop = ControlLoop(LoopConfig(n_robots=n), source=source, sink=robots, clock=time.monotonic)
        pacer = RealTimePacer(0.033)
        frames = []
        for _ in range(75):  # 2.5 s at 30 Hz
            frames.append(loop.tick())
            pacer.wait()
        costs = [f.coverage.cost_H for f in frames if f.coverage is not None]
        assert len(costs) > 50 and costs[-1] < costs[0]  # the swarm covers
        assert all(f.barrier is None or f.barrier.ok for f in frames)
        assert all(len(colliding_pairs(f.poses)) == 0 for f in frames)
        moved = np.linalg.norm(frames[-1].poses[:, :2] - frames[0].poses[:, :2], axis=1)
        assert np.all(moved > 0.005)
        assert "connected" in frames[-1].health["robots"]
        assert robots.streamer.counters.get("undelivered_ticks") == 0
    finally:
        if robots is not None:
            robots.close()  # console stops: zero once, then silence
    # the fleet's robots stand still from now on: their poses stop changing
    try:
        probe = MqttTransport(parse_broker_url(mosquitto.url), ids=range(n)).start()
        try:
            # The console's final zero may be overtaken under load; the firmware's 500 ms
            # timeout stops the robots regardless. 20 pose messages at 30 Hz span > 0.6 s.
            wait_until(lambda: probe.counters.get("pose_messages") >= 20, 10, "0.6 s of pose messages")
            first = probe.latest_poses().poses
            wait_until(lambda: probe.counters.get("pose_messages") >= 35, 10, "more pose messages")
            last = probe.latest_poses().poses
        finally:
            probe.close()
        assert np.array_equal(first, last)
    finally:
        fleet.terminate()
        fleet.communicate(timeout=10)
