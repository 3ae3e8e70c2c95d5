"""The console-side watchdogs: stale poses and stale inputs give zero commands, on the wire and in-process."""
from __future__ import annotations

import json

import numpy as np
import pytest
from mqtt_broker import Collector, wait_until

from swarmdeck.devices import ArenaConfig, SimulatedArena
from swarmdeck.devices.clock import VirtualClock
from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.net.streamer import CommandStreamer, StreamerConfig
from swarmdeck.devices.net.transport_inprocess import InProcessTransport
from swarmdeck.devices.net.transport_mqtt import MqttTransport
from swarmdeck.devices.net.wire import encode_poses


@pytest.mark.mqtt
def test_stale_pose_zeroes_only_that_robot_on_the_wire(mosquitto):
    clock = VirtualClock()  # receive stamps and watchdog time both on a virtual clock
    raw = Collector(mosquitto, ["matlab_api/#"])
    transport = MqttTransport(parse_broker_url(mosquitto.url), ids=[0, 1], clock=lambda: clock.now).start()
    streamer = CommandStreamer(transport, transport, StreamerConfig(pose_timeout=0.1, input_timeout=10.0),
                               clock=lambda: clock.now)
    tracker = "overhead_tracker/all_robot_pose_data"
    try:
        assert transport.link.wait_connected(10)
        raw.publish(tracker, encode_poses([0, 1], np.zeros((2, 3)) + [[0.5, 0, 0], [-0.5, 0, 0]], [4.0, 4.0], [False, False]))
        wait_until(lambda: len(transport.latest_poses().ids) == 2, what="first poses")
        clock.now = 1.0
        raw.publish(tracker, encode_poses([1], [[-0.5, 0.01, 0.0]], [4.0], [False]))  # robot 0 no longer seen
        wait_until(lambda: transport.latest_poses().stamps[1] == 1.0, what="second poses")
        streamer.submit([0, 1], [0.1, 0.1], [0.2, 0.2], stamp=1.0)
        tick = streamer.tick(now=1.05)
        assert tick.stale_pose.tolist() == [True, False]
        msgs = raw.wait_for(lambda m: len(m) >= 2)
    finally:
        transport.close()
        raw.close()
    assert [(t, json.loads(p)) for t, p in msgs[:2]] == [
        ("matlab_api/0", {"v": 0.0, "w": 0.0}),
        ("matlab_api/1", {"v": 0.1, "w": 0.2}),
    ]
    assert streamer.counters.get("stale_pose_robot_ticks") == 1
    assert any("robot(s) [0]" in e and "pose older" in e for e in streamer.events)


def make_inprocess(n: int = 3) -> tuple[InProcessTransport, CommandStreamer]:
    arena = SimulatedArena(n, config=ArenaConfig(seed=2))
    transport = InProcessTransport(arena)
    streamer = CommandStreamer(transport, transport, StreamerConfig(input_timeout=0.1), clock=lambda: transport.time)
    return transport, streamer


def test_stale_inputs_stop_every_robot_until_fresh_commands_arrive():
    transport, streamer = make_inprocess()
    streamer.submit([0, 1, 2], [0.1] * 3, [0.0] * 3)  # stamped t = 0
    moved = []
    for _ in range(8):  # 8 ticks of 0.033 s: inputs go stale after 0.1 s
        before = transport.latest_poses().poses
        tick = streamer.tick()
        moved.append(bool(np.any(transport.latest_poses().poses != before)))
        assert tick.stale_input.all() == (tick.t > 0.1 + 1e-12)
    assert moved == [True, True, True, True, False, False, False, False]
    assert streamer.counters.get("stale_input_robot_ticks") == 3 * 4
    streamer.submit([0, 1, 2], [0.1] * 3, [0.0] * 3)
    before = transport.latest_poses().poses
    assert not streamer.tick().stale_input.any()
    assert np.all(transport.latest_poses().poses[:, :2] != before[:, :2])
    assert any("commands fresh again" in e for e in streamer.events)


def test_inputs_carry_their_own_timeout():
    transport, streamer = make_inprocess()
    streamer.submit([0, 1, 2], [0.05] * 3, [0.0] * 3, valid_for=0.3)
    ticks = [streamer.tick() for _ in range(12)]
    stale = [t.stale_input.all() for t in ticks]
    assert stale == [t.t > 0.3 + 1e-12 for t in ticks] and any(stale) and not all(stale)


def test_bad_input_is_counted_and_stops_only_the_affected_robots():
    transport, streamer = make_inprocess()
    streamer.submit([0, 1, 2], [0.1, np.nan, 0.1], [0.0, 0.0, np.inf])
    tick = streamer.tick()
    assert tick.v.tolist() == [0.1, 0.0, 0.0]
    streamer.submit([0, 0, 1], [0.1, 0.1, 0.1], [0.0, 0.0, 0.0])  # robot 0 named twice: ambiguous, stopped
    tick = streamer.tick()
    assert dict(zip(tick.ids.tolist(), tick.v.tolist())) == {0: 0.0, 1: 0.1}
    streamer.submit([0, 1, 2], [0.1, 0.1], [0.0, 0.0, 0.0])  # wrong length: everyone stopped
    assert np.all(streamer.tick().v == 0)
    transport.send([7], [0.1], [0.0])  # unknown id: counted, the others stand still
    assert streamer.counters.get("bad_input") == 3
    assert transport.status().counters["unknown_id"] == 1
    assert "unknown robot id(s) [7]" in transport.status().last_error
