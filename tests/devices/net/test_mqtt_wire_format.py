"""Message-level check of the GRITSBot X wire format (REFERENCE.md §9) on a real mosquitto.

A raw paho client, independent of swarmdeck's MQTT code, records what the
console transport and the simulated fleet put on the wire, and speaks to the
fleet the way the Robotarium's backend does.
"""
from __future__ import annotations

import json

import numpy as np
import pytest
from mqtt_broker import Collector, wait_until

from swarmdeck.devices.net.fleet import FleetNode
from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.net.transport_mqtt import MqttTransport

pytestmark = pytest.mark.mqtt


@pytest.mark.parametrize("protocol, qos", [("3.1.1", 0), ("5", 1)])
def test_console_commands_on_the_wire(mosquitto, protocol, qos):
    raw = Collector(mosquitto, ["matlab_api/#"])
    transport = MqttTransport(parse_broker_url(mosquitto.url, protocol=protocol, qos=qos), ids=[0, 1, 2]).start()
    try:
        assert transport.link.wait_connected(10)
        assert transport.send([0, 1, 2], [0.1, -0.05, 0.0], [0.5, 0.0, -1.25])
        assert transport.send([2], [0.2], [0.0], leds=[[[255, 0, 0], [0, 0, 255]]])
        msgs = raw.wait_for(lambda m: len(m) >= 4)
    finally:
        transport.close()
        raw.close()
    first = {t: json.loads(p) for t, p in msgs[:3]}
    assert first == {
        "matlab_api/0": {"v": 0.1, "w": 0.5},
        "matlab_api/1": {"v": -0.05, "w": 0.0},
        "matlab_api/2": {"v": 0.0, "w": -1.25},
    }
    topic, payload = msgs[3]
    assert topic == "matlab_api/2"
    assert json.loads(payload) == {"v": 0.2, "w": 0.0, "left_led": [255, 0, 0], "right_led": [0, 0, 255]}


def test_fleet_poses_and_status_on_the_wire_and_robotarium_commands_in(mosquitto):
    raw = Collector(mosquitto, ["overhead_tracker/all_robot_pose_data", "+/status"])
    cfg = parse_broker_url(mosquitto.url)
    poses = np.array([[0.5, 0.25, 0.0], [-0.5, -0.25, np.pi / 2]])
    fleet = FleetNode(cfg, [3, 4], poses, name="fleet-under-test").start()
    try:
        msgs = raw.wait_for(lambda m: {t for t, _ in m} >= {"overhead_tracker/all_robot_pose_data", "3/status", "4/status"})
        pose_msgs = [json.loads(p) for t, p in msgs if t == "overhead_tracker/all_robot_pose_data"]
        pm = pose_msgs[0]
        assert set(pm) == {"3", "4"}
        for rid in ("3", "4"):
            assert {"x", "y", "theta", "batt_volt", "charge_status"} <= set(pm[rid])
            assert isinstance(pm[rid]["charge_status"], bool)
        assert (pm["3"]["x"], pm["3"]["y"], pm["3"]["theta"]) == (0.5, 0.25, 0.0)
        assert (pm["4"]["x"], pm["4"]["y"], pm["4"]["theta"]) == (-0.5, -0.25, round(np.pi / 2, 3))
        st = json.loads(next(p for t, p in msgs if t == "3/status"))
        assert {"batt_volt", "charge_status"} <= set(st) and 3.3 <= st["batt_volt"] <= 4.2
        assert st["node"] == "fleet-under-test"
        # The Robotarium backend's command, LEDs included, drives robot 4; a malformed one is dropped.
        raw.publish("matlab_api/4", b'{"v": 0.1, "w": 0.0, "left_led": [0, 255, 0], "right_led": [0, 255, 0]}')
        raw.publish("matlab_api/3", b'{"v": "oops"}')
        wait_until(lambda: fleet.snapshot()["commands_received"][1] == 1 and fleet.counters.get("malformed_command") == 1,
                   what="fleet received both commands")
        assert fleet.state.leds[1].tolist() == [[0, 255, 0], [0, 255, 0]]
        assert fleet.snapshot()["commands_received"][0] == 0
        # robot 4 heads +y: after its 0.5 s of motion it stands 0.05 m further up
        wait_until(lambda: fleet.snapshot()["timeouts"][1] == 1, what="firmware brake")
        assert np.allclose(fleet.snapshot()["poses"][1, :2], [-0.5, -0.25 + 0.05], atol=1e-9)
    finally:
        fleet.stop()
        raw.close()
