"""Bad input from the network: clear messages, counted, never an exception into the loop."""
from __future__ import annotations

import json

import numpy as np
import pytest
from mqtt_broker import Collector, free_port, wait_until

from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.net.streamer import CommandStreamer, StreamerConfig
from swarmdeck.devices.net.transport_mqtt import MqttTransport
from swarmdeck.devices.net.wire import encode_poses, encode_status

pytestmark = pytest.mark.mqtt
TRACKER = "overhead_tracker/all_robot_pose_data"


def test_refused_connection_is_reported_not_raised():
    transport = MqttTransport(parse_broker_url(f"mqtt://127.0.0.1:{free_port()}"), ids=[0, 1]).start()
    try:
        wait_until(lambda: transport.counters.get("connect_failed") >= 1, 10, "first failed connection attempt")
        assert transport.send([0, 1], [0.1, 0.1], [0.0, 0.0]) is False
        st = transport.status()
        assert not st.connected and "cannot reach broker" in st.state
        assert st.counters["undeliverable"] == 2
        streamer = CommandStreamer(transport, transport)
        streamer.submit([0, 1], [0.1, 0.1], [0.0, 0.0])
        tick = streamer.tick()
        assert not tick.delivered and tick.stale_pose.all()  # never seen: zero, and not delivered anyway
        assert any("cannot be delivered" in e for e in streamer.events)
    finally:
        transport.close()


def test_malformed_unknown_and_out_of_order_messages_are_counted(mosquitto):
    raw = Collector(mosquitto, ["matlab_api/#"])
    transport = MqttTransport(parse_broker_url(mosquitto.url), ids=[0, 1, 2]).start()
    try:
        assert transport.link.wait_connected(10)
        raw.publish("0/status", b'{"batt_volt": 4.1, "charge_status": fal')
        raw.publish("9/status", encode_status(4.0, False))
        raw.publish(TRACKER, b"[]")
        raw.publish(TRACKER, json.dumps({"1": {"x": 0.2, "y": 0.1, "theta": 0.0, "stamp": 2.0},
                                         "x": {"x": 0, "y": 0, "theta": 0},
                                         "7": {"x": 0, "y": 0, "theta": 0}}).encode())
        raw.publish(TRACKER, encode_poses([1], [[0.9, 0.9, 0.0]], [4.0], [False], stamp=1.0))  # older stamp
        raw.publish("1/status", encode_status(4.0, False, seq=5, node="n"))
        raw.publish("1/status", encode_status(3.5, False, seq=3, node="n"))  # older report
        raw.publish("2/status", encode_status(4.0, False, seq=1, node="fleet-a"))
        raw.publish("2/status", encode_status(4.0, False, seq=1, node="fleet-b"))  # a second robot claims id 2

        def counted():
            c = transport.status().counters
            return c if c.get("out_of_order", 0) >= 2 and c.get("duplicate_id", 0) >= 1 else None

        c = wait_until(counted, 10, "every bad message counted")
        assert c["malformed_status"] == 1
        assert c["malformed_poses"] == 1
        assert c["bad_pose_rows"] == 1
        assert c["unknown_id"] == 2  # status of 9, pose row of 7
        assert c["out_of_order"] == 2
        poses = transport.latest_poses()
        assert poses.ids.tolist() == [1] and np.allclose(poses.poses[0], [0.2, 0.1, 0.0])
        st = transport.status()
        assert st.robots.battery_voltage[1] == 4.0
        assert st.robots.link[2] == "duplicate" and 2 in transport.excluded().tolist()
        assert "duplicate robot id 2" in (st.last_error or "") or "duplicate robot id 2" in str(st.to_dict())
        # the streamer zeroes the duplicated id on the wire
        streamer = CommandStreamer(transport, None, StreamerConfig())
        streamer.submit([1, 2], [0.1, 0.1], [0.0, 0.0])
        tick = streamer.tick()
        assert tick.excluded.tolist() == [False, True]
        msgs = raw.wait_for(lambda m: len(m) >= 2)
        assert dict((t, json.loads(p)) for t, p in msgs[:2]) == {
            "matlab_api/1": {"v": 0.1, "w": 0.0}, "matlab_api/2": {"v": 0.0, "w": 0.0}}
        json.dumps(st.to_dict())  # the status is JSON-able for the console panel
    finally:
        transport.close()
        raw.close()


def test_experiment_backend_names_robots_that_never_sent_a_pose(mosquitto):
    from swarmdeck.devices.net.console_robots import NetworkRobots

    with pytest.raises(ValueError, match=r"no pose from robot id\(s\) \[0, 1\].*swarmdeck robots"):
        NetworkRobots.connect(mosquitto.url, n_robots=2, wait_for_poses=0.3)
