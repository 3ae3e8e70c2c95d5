"""`swarmdeck robots` as its own process, driven over a real mosquitto by the console-side transport."""
from __future__ import annotations

import subprocess
import sys
import time

import numpy as np
import pytest
from mqtt_broker import wait_until

from swarmdeck.core.kinematics import unicycle_step, wrap_angle
from swarmdeck.devices import Arena
from swarmdeck.devices.net.console_robots import NetworkRobots
from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.net.transport_mqtt import LinkTimeouts, MqttTransport

pytestmark = pytest.mark.mqtt


def start_fleet(url: str, *extra: str) -> subprocess.Popen:
    cmd = [sys.executable, "-c", "import sys; from swarmdeck.console.cli import main; sys.exit(main())",
           "robots", "--broker", url, "--quiet", *extra]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def stop_fleet(proc: subprocess.Popen) -> tuple[int, str]:
    proc.terminate()
    try:
        out, err = proc.communicate(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
    return proc.returncode, out + err


def test_firmware_stops_500ms_after_the_last_command(mosquitto):
    fleet = start_fleet(mosquitto.url, "--robots", "3", "--seed", "4")
    transport = MqttTransport(parse_broker_url(mosquitto.url), ids=[0, 1, 2]).start()
    try:
        sample = wait_until(lambda: (s := transport.latest_poses()) and len(s.ids) == 3 and s, 15, "poses of 3 robots")
        p0 = sample.poses.copy()
        assert transport.send([1], [0.1], [1.0])  # one command, then silence

        def final_pose():
            # a status report sent after the brake (cmd_age > 0.5 s), then a pose message received after it
            st = transport.status().robots
            age = st.command_age[1] - st.status_age[1]  # as reported by the robot, at its report
            if not (np.isfinite(age) and age > 0.5):
                return None
            t_status = time.monotonic() - st.status_age[1]
            s = transport.latest_poses()
            return (s.poses.copy(),) if s.stamps[1] > t_status else None

        (p1,) = wait_until(final_pose, 10, "status report after the firmware brake")
    finally:
        transport.close()
        code, log = stop_fleet(fleet)
    expected = unicycle_step(p0[1:2], np.array([0.1 * 0.5]), np.array([1.0 * 0.5]), 1.0)[0]
    assert np.allclose(p1[1, :2], expected[:2], atol=2e-3), (p1[1], expected)
    assert abs(wrap_angle(p1[1, 2] - expected[2])) < 2e-3
    assert np.allclose(p1[[0, 2]], p0[[0, 2]])  # robots not commanded never moved
    assert code == 0, log


def test_arena_drives_the_fleet_process_and_loses_it_when_it_stops(mosquitto):
    fleet = start_fleet(mosquitto.url, "--robots", "4", "--seed", "5")
    transport = MqttTransport(parse_broker_url(mosquitto.url), ids=range(4),
                              timeouts=LinkTimeouts(missing_after=0.6)).start()
    backend = None
    try:
        backend = NetworkRobots(transport, np.arange(4), background=False)
        wait_until(lambda: len(transport.latest_poses().ids) == 4, 15, "a pose from every robot")
        arena = Arena(backend=backend, safety=False)
        start = arena.positions()
        goals = start + np.array([0.06, 0.0])
        arena.set_goals(goals)
        for _ in range(60):  # 2 s at 30 Hz
            arena.step()
        err0 = np.linalg.norm(start - goals, axis=1)
        err1 = np.linalg.norm(arena.positions() - goals, axis=1)
        assert np.all(err1 < 0.5 * err0), (err0, err1)
        assert backend.streamer.counters.get("undelivered_ticks") == 0
        code, log = stop_fleet(fleet)
        assert code == 0, log
        wait_until(lambda: len(transport.excluded()) == 4, 10, "robots marked missing after their fleet stopped")
        last = transport.latest_poses().poses  # their last reported poses (the fleet may report after the last step)
        obstacles = backend.obstacles()
        assert np.allclose(np.sort(obstacles, axis=0), np.sort(last[:, :2], axis=0))
        tick = backend.streamer.tick()
        assert tick.excluded.all() and np.all(tick.v == 0) and np.all(tick.w == 0)
        assert any("excluded from control" in e for e in backend.streamer.events)
    finally:
        if fleet.poll() is None:
            stop_fleet(fleet)
        if backend is not None:
            backend.close()
        else:
            transport.close()
