"""Encoding and decoding of the GRITSBot X JSON payloads, without a broker."""
from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.net.transport import check_command
from swarmdeck.devices.net.wire import (
    WireError,
    decode_command,
    decode_poses,
    decode_status,
    encode_commands,
    encode_poses,
    encode_status,
)

finite = st.floats(-5, 5, allow_nan=False, allow_infinity=False)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.tuples(finite, finite), min_size=1, max_size=20), st.booleans())
def test_commands_round_trip_exactly(vw, with_leds):
    v = np.array([a for a, _ in vw])
    w = np.array([b for _, b in vw])
    leds = np.arange(len(vw) * 6, dtype=np.uint8).reshape(-1, 2, 3) if with_leds else None
    for k, payload in enumerate(encode_commands(v, w, leds)):
        cmd = decode_command(payload)
        assert cmd.v == v[k] and cmd.w == w[k]
        obj = json.loads(payload)
        assert set(obj) == ({"v", "w", "left_led", "right_led"} if with_leds else {"v", "w"})
        if with_leds:
            assert cmd.left_led == tuple(leds[k, 0].tolist()) and cmd.right_led == tuple(leds[k, 1].tolist())


@pytest.mark.parametrize(
    "payload, fragment",
    [
        (b"{not json", "not valid JSON"),
        (b"[1, 2]", "expected a JSON object"),
        (b'{"v": 0.1}', "missing key 'w'"),
        (b'{"v": "fast", "w": 0}', "'v' must be a finite number"),
        (b'{"v": true, "w": 0}', "'v' must be a finite number"),
        (b'{"v": NaN, "w": 0}', "'v' must be a finite number"),
        (b'{"v": 0, "w": 0, "left_led": [300, 0, 0]}', "integers 0..255"),
        (b"\xff\xfe", "not valid JSON"),
    ],
)
def test_malformed_commands_raise_wire_error_naming_the_problem(payload, fragment):
    with pytest.raises(WireError, match=fragment):
        decode_command(payload)


def test_status_round_trip_and_robotarium_minimum():
    st_ = decode_status(encode_status(3.91, True, cmd_age=0.25, seq=7, node="fleet-a", stamp=12.5))
    assert (st_.batt_volt, st_.charge_status, st_.cmd_age, st_.seq, st_.node, st_.stamp) == (3.91, True, 0.25, 7, "fleet-a", 12.5)
    bare = decode_status(b'{"batt_volt": 4.0, "charge_status": 0}')  # what a real robot sends
    assert bare.batt_volt == 4.0 and bare.charge_status is False and bare.seq is None
    for bad, frag in [(b'{"charge_status": true}', "batt_volt"), (b'{"batt_volt": 4, "charge_status": "maybe"}', "charge_status"),
                      (b'{"batt_volt": 4, "charge_status": true, "seq": 1.5}', "seq")]:
        with pytest.raises(WireError, match=frag):
            decode_status(bad)


@settings(max_examples=30, deadline=None)
@given(st.lists(st.integers(0, 500), min_size=0, max_size=30, unique=True), st.integers(0, 10_000))
def test_poses_round_trip_to_the_published_precision(ids, seed):
    rng = np.random.default_rng(seed)
    poses = rng.uniform([-1.6, -1, -np.pi], [1.6, 1, np.pi], (len(ids), 3))
    batt = rng.uniform(3.3, 4.2, len(ids))
    msg = decode_poses(encode_poses(ids, poses, batt, np.zeros(len(ids), bool), decimals=3, stamp=1.25))
    order = np.argsort(ids)
    assert msg.ids.tolist() == sorted(ids)
    assert np.allclose(msg.poses, poses[order], atol=5e-4 + 1e-12)
    assert np.allclose(msg.batt_volt, batt[order], atol=5e-4 + 1e-12)
    assert np.all(msg.stamps == 1.25) and not msg.problems


def test_bad_pose_rows_are_skipped_and_described():
    payload = json.dumps({
        "3": {"x": 0.1, "y": 0.2, "theta": 0.3, "batt_volt": 4.1, "charge_status": False},
        "robot7": {"x": 0, "y": 0, "theta": 0},
        "4": {"x": 0.1, "y": "north", "theta": 0},
        "5": [1, 2, 3],
    }).encode()
    msg = decode_poses(payload)
    assert msg.ids.tolist() == [3]
    assert len(msg.problems) == 3
    assert any("'robot7'" in p for p in msg.problems) and any("robot 4" in p for p in msg.problems)


def test_check_command_never_raises_and_stops_what_is_ambiguous():
    c = check_command([1, 2, 2, -1, 5], [0.1, 0.2, 0.3, 0.1, np.nan], [0, 0, 0, 0, 0])
    assert c.ids.tolist() == [1, 2, 5]
    assert c.v.tolist() == [0.1, 0.0, 0.0]  # duplicated 2 and NaN 5 stopped
    assert len(c.problems) == 3
    c = check_command([0, 1], [0.1], [0.0, 0.0])
    assert c.v.tolist() == [0.0, 0.0] and c.zeroed.all()
    c = check_command(["a"], [0.1], [0.0])
    assert len(c.ids) == 0 and "integers" in c.problems[0]
    c = check_command([0], [0.1], [0.2], leds=[[10, 20, 30]])
    assert c.leds.shape == (1, 2, 3) and c.leds[0, 1].tolist() == [10, 20, 30]


def test_broker_urls():
    c = parse_broker_url("mqtt://alice:s%40cret@lab.example:1884/arena2/", qos=1, protocol="5")
    assert (c.host, c.port, c.username, c.password, c.prefix, c.qos, c.protocol, c.tls) == (
        "lab.example", 1884, "alice", "s@cret", "arena2/", 1, "5", False)
    assert c.command_topic(3) == "arena2/matlab_api/3" and c.status_topic(3) == "arena2/3/status"
    assert c.robot_id_of_status_topic("arena2/17/status") == 17 and c.robot_id_of_command_topic("arena2/matlab_api/x") is None
    assert parse_broker_url("mqtts://h").port == 8883 and parse_broker_url("mqtts://h").tls
    plain = parse_broker_url("mqtt://127.0.0.1:1883")
    assert plain.command_topic(0) == "matlab_api/0" and plain.pose_topic == "overhead_tracker/all_robot_pose_data"
    for bad in ["http://x:1", "mqtt://:1883", "mqtt://h:99999", "mqtt://h:1/a+b/"]:
        with pytest.raises(ValueError):
            parse_broker_url(bad)
