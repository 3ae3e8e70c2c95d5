"""Kill the broker mid-run: robots brake within 0.5 s, the console reconnects, the swarm resumes, nobody collides."""
from __future__ import annotations

import threading
import time

import numpy as np
import pytest
from mqtt_broker import wait_until

from swarmdeck.devices import colliding_pairs, lookahead_points, random_initial_poses, si_to_unicycle
from swarmdeck.devices.controllers import si_position_controller
from swarmdeck.devices.net.fleet import FleetNode
from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.net.streamer import CommandStreamer
from swarmdeck.devices.net.transport_mqtt import MqttTransport

pytestmark = pytest.mark.mqtt


def test_broker_restart_mid_run(mosquitto):
    n = 6
    ids = np.arange(n)
    cfg = parse_broker_url(mosquitto.url)
    start = random_initial_poses(n, rng=11)
    fleet = FleetNode(cfg, ids, start, name="fleet-restart").start()
    transport = MqttTransport(cfg, ids=ids).start()
    streamer = CommandStreamer(transport, transport).start()
    centres = lookahead_points(start, 0.03)
    done = threading.Event()
    seen_poses: list[np.ndarray] = []

    def control() -> None:  # the console's loop: orbit 4 cm circles around the start points
        t0 = time.monotonic()
        while not done.is_set():
            t = time.monotonic() - t0
            poses, _ = transport.latest_poses().select(ids)
            if np.all(np.isfinite(poses)):
                goals = centres + 0.04 * np.array([np.cos(t), np.sin(t)])
                v, w = si_to_unicycle(poses, si_position_controller(lookahead_points(poses, 0.03), goals, gain=2.0), 0.03)
                streamer.submit(ids, v, w)
            seen_poses.append(fleet.snapshot()["poses"])
            done.wait(0.033)

    loop = threading.Thread(target=control, daemon=True)
    loop.start()
    try:
        def all_moving() -> bool:
            s = fleet.snapshot()
            return bool(np.all((s["v"] != 0) | (s["w"] != 0)))

        wait_until(all_moving, 10, "robots moving under console control")
        mosquitto.kill()

        def all_stopped():
            s = fleet.snapshot()
            return s if np.all((s["v"] == 0) & (s["w"] == 0)) else None

        stopped = wait_until(all_stopped, 5, "robots braking after the broker died")
        # They stopped by their own firmware brake (exactly 0.5 s after the last command, in the
        # fleet model's time: tests/devices/test_devices_transport_fleet_model.py), not by a zero command,
        # and stay stopped with no command arriving while the broker is down (no wall-clock bounds).
        assert np.all(stopped["timeouts"] >= 1)
        wait_until(lambda: not transport.status().connected, 5, "console noticing the lost broker")
        assert "broker" in transport.status().state
        wait_until(lambda: streamer.counters.get("undelivered_ticks") > 0, 5, "streamer counting undelivered ticks")
        received_at_kill = stopped["commands_received"].copy()
        down = fleet.snapshot()
        assert np.array_equal(down["commands_received"], received_at_kill)
        assert np.all((down["v"] == 0) & (down["w"] == 0))

        mosquitto.start()
        wait_until(lambda: transport.status().connected and fleet.link.connected, 15, "both sides reconnected")
        wait_until(lambda: np.all(fleet.snapshot()["commands_received"] > received_at_kill) and all_moving(), 10,
                   "robots moving again after reconnection")
        assert transport.counters.get("reconnects") >= 1 and fleet.counters.get("reconnects") >= 1
        assert any("cannot be delivered" in e for e in streamer.events)
        assert any("delivered again" in e for e in streamer.events)
    finally:
        done.set()
        loop.join(2)
        streamer.stop()
        transport.close()
        fleet.stop()
    assert len(seen_poses) > 10
    assert all(len(colliding_pairs(p)) == 0 for p in seen_poses)
