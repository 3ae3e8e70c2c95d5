"""Link states of the MQTT transport on a virtual clock: ok, stale, missing, unknown, duplicate.

robots(), excluded() and status() must agree on every robot (no broker needed: messages are fed
to the transport's receive path directly, as the paho thread would).
"""
import json

import numpy as np

from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.net.transport_mqtt import MqttTransport
from swarmdeck.devices.net.wire import encode_status


class Clock:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


def _poses(ids) -> bytes:
    return json.dumps({str(i): {"x": 0.1 * i, "y": 0.0, "theta": 0.0} for i in ids}).encode()


def test_every_state_and_the_views_agree():
    clock = Clock()
    tr = MqttTransport(parse_broker_url("mqtt://127.0.0.1:1"), ids=[0, 1, 2, 3, 4], clock=clock)
    cfg = tr.config
    tr._on_message(cfg.pose_topic, _poses([0, 1, 2, 4]), clock.t)
    tr._on_message(cfg.status_topic(2), encode_status(4.1, False, node="a"), clock.t)
    tr._on_message(cfg.status_topic(2), encode_status(4.1, False, node="b"), clock.t)  # a second node claims 2
    clock.t += 0.05
    tr._on_message(cfg.pose_topic, _poses([0, 1]), clock.t)
    clock.t += 0.09  # 4's pose is now 0.14 s old: stale; 0 and 1 are 0.09 s old: ok
    st = tr.status().robots
    links = dict(zip(st.ids.tolist(), st.link))
    assert links == {0: "ok", 1: "ok", 2: "duplicate", 3: "unknown", 4: "stale"}
    assert tr.robots().tolist() == [0, 1, 4]
    assert tr.excluded().tolist() == [2]
    clock.t += 3.0  # nothing heard for longer than missing_after
    tr._on_message(cfg.pose_topic, _poses([0]), clock.t)
    st = tr.status().robots
    assert dict(zip(st.ids.tolist(), st.link)) == {0: "ok", 1: "missing", 2: "duplicate", 3: "unknown", 4: "missing"}
    assert tr.robots().tolist() == [0] and tr.excluded().tolist() == [1, 2, 4]


def test_unknown_ids_are_counted_not_stored():
    clock = Clock()
    tr = MqttTransport(parse_broker_url("mqtt://127.0.0.1:1"), ids=[0, 1], clock=clock)
    tr._on_message(tr.config.pose_topic, _poses([0, 1, 7, 9]), clock.t)
    assert tr.latest_poses().ids.tolist() == [0, 1]
    assert tr.status().counters["unknown_id"] == 2
    assert tr.send(np.array([1, 7]), np.zeros(2), np.zeros(2)) is False  # 7 unknown (and not connected)
    assert tr.status().counters["unknown_id"] == 3
