"""The messages that carry a sandboxed script's sensors, LEDs, network and obstacles across the trust boundary:
what the trusted side sends round-trips exactly, and anything malformed the child sends is refused with a
ProtocolError naming what was wrong (never a crash of the trusted side)."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.console.sandbox.network_link import (
    RemoteNetwork,
    TrustedNetwork,
    network_config_from_message,
    network_config_message,
)
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.protocol import ProtocolError, obstacles
from swarmdeck.console.sandbox.run import _make_plant
from swarmdeck.console.sandbox.senses import (
    leds_from_message,
    leds_message,
    readings_from_message,
    readings_message,
    sensing_from_message,
    sensing_message,
)
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.simulator import ArenaConfig
from swarmdeck.network import (
    BernoulliLoss,
    DiskTopology,
    FixedTopology,
    GilbertElliottLoss,
    KNearestTopology,
    NetworkConfig,
)
from swarmdeck.network.payload import encode_payload
from swarmdeck.sensing import SensingConfig, Sensors
from swarmdeck.sensing.config import DistanceSensorConfig, RangeBearingConfig

POSES = np.array([[-0.5, 0.0, 0.0], [0.0, 0.1, 1.0], [0.4, -0.2, 3.0]])


def test_sensing_configurations_and_readings_round_trip():
    config = SensingConfig(distance=DistanceSensorConfig(max_range=0.8), range_bearing=RangeBearingConfig(radius=1.0))
    assert sensing_from_message(sensing_message(config)) == config
    sensors = Sensors(3, config, rng=np.random.default_rng(1), obstacles=[[[0.2, -0.5], [0.2, 0.5]]])
    sensors.first(POSES)
    sent = sensors.update(POSES + 0.01, np.full(3, 0.1), np.zeros(3), 0.033)
    got = readings_from_message(readings_message(4, sent))
    for name in ("distances", "origins", "endpoints", "encoders", "accel", "gyro", "mag", "orientation", "leds"):
        np.testing.assert_array_equal(getattr(got, name), getattr(sent, name), err_msg=name)
    assert got.robot(1).keys() == sent.robot(1).keys() and got.robot(1)["neighbours"] == sent.robot(1)["neighbours"]


@pytest.mark.parametrize(("config", "words"), [
    ("nope", "config must be a map"),
    ({"distance": {"max_range": -1.0}}, "max_range"),
    ({"distance": {"colour": 1}}, "distance"),
    ({"distance": {"poses": [[0.0, 0.0, 0.0]] * 65}}, "at most 64"),
    ({"imu": 3}, "imu must be a map"),
    ({"radar": {}}, "config must be a map"),
])
def test_a_bad_sensors_message_is_named(config, words):
    with pytest.raises(ProtocolError, match=words):
        sensing_from_message({"t": "sensors", "config": config})


def test_leds_are_checked():
    rgb = np.array([[255, 0, 0], [0, 255, 0], [0, 0, 255]], dtype=np.uint8)
    np.testing.assert_array_equal(leds_from_message(leds_message(rgb), 3), rgb)
    with pytest.raises(ProtocolError, match="rgb must be 9 bytes"):
        leds_from_message({"t": "leds", "rgb": b"\0" * 8}, 3)


@pytest.mark.parametrize("config", [
    NetworkConfig(topology=DiskTopology(0.4), latency=2, jitter=1, loss=BernoulliLoss(0.2), bandwidth=900, seed=3),
    NetworkConfig(topology=KNearestTopology(2), loss=GilbertElliottLoss(0.1, 0.3, 0.01, 0.9)),
    NetworkConfig(topology=FixedTopology.from_edges([[0, 1], [1, 2]]), max_messages_per_tick=4),
])
def test_network_configurations_round_trip(config):
    assert network_config_from_message(network_config_message(config)) == config


def test_a_bad_network_configuration_is_named():
    good = network_config_message(NetworkConfig())
    with pytest.raises(ProtocolError, match="delta"):
        network_config_from_message({**good, "topology": {"kind": "disk", "delta": -1.0}})
    with pytest.raises(ProtocolError, match="latency"):
        network_config_from_message({**good, "latency": 10**6})
    with pytest.raises(ProtocolError, match="unknown topology"):
        network_config_from_message({**good, "topology": {"kind": "mesh"}})

    class Everyone:
        def links(self, positions):
            return np.zeros((0, 2), dtype=np.intp)

    with pytest.raises(ValueError, match="FixedTopology, DiskTopology or KNearestTopology"):
        network_config_message(NetworkConfig(topology=Everyone()))


def test_the_trusted_network_counts_what_it_refuses_and_delivers_the_rest():
    trusted = TrustedNetwork(3, NetworkConfig(topology=KNearestTopology(2)), POSES[:, :2])
    data = encode_payload([1.0, 2.0], 4096)
    trusted.post({"t": "outbox", "messages": [[0, -1, data], [1, 99, data], [2, 2, data], [1, 0, b"\xc1"]]})
    trusted.step(POSES[:, :2])
    remote = RemoteNetwork(3, trusted.config)
    remote.deliver(trusted.inboxes_message(1))
    assert [m.payload for m in remote.inbox(1)] == [[1.0, 2.0]] and remote.inbox(1)[0].sender == 0
    assert remote.stats["refused:unknown_robot"] + remote.stats["refused:bad_id"] + remote.stats["refused:self"] >= 1
    np.testing.assert_array_equal(remote.neighbours(0), trusted.network.neighbours(0))
    with pytest.raises(ProtocolError, match="at most 192"):
        trusted.post({"t": "outbox", "messages": [[0, 1, data]] * 193})
    with pytest.raises(ProtocolError, match=r"\[sender, receiver"):
        trusted.post({"t": "outbox", "messages": [[0, "1", data]]})


def test_declared_obstacles_are_checked_before_they_are_solid():
    with pytest.raises(ProtocolError, match="m .*1..4096"):
        obstacles({"t": "arena", "m": 0, "obstacles": b""})
    with pytest.raises(ProtocolError, match="'obstacles' has 8 bytes"):
        obstacles({"t": "arena", "m": 1, "obstacles": b"\0" * 8})

    def plant(n, initial):
        return ArenaPlant(Arena(n, initial_conditions=initial, config=ArenaConfig(seed=1)))

    across = np.array([[[0.0, -0.3], [0.0, 0.3]]])
    with pytest.raises(ValueError, match="segment 0"):  # across robot 1's start pose: the Arena is refused
        _make_plant(plant, 3, POSES, across)
    with pytest.raises(ValueError, match="NaN|finite"):
        _make_plant(plant, 3, POSES, np.array([[[1.0, np.nan], [1.2, 0.5]]]))
    made = _make_plant(plant, 3, POSES, np.array([[[1.0, -0.5], [1.0, 0.5]]]))
    assert made.arena.config.obstacles.m == 1 and made.arena.safety is not None


def test_the_portal_loop_plant_senses_for_a_script_from_its_frames():
    from swarmdeck.console.portal.runner import SandboxCommands
    from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
    from swarmdeck.console.sandbox.plant import SandboxPlant

    loop = ControlLoop(LoopConfig(n_robots=3, seed=1))
    try:
        commands = SandboxCommands()
        loop.use_behaviour(commands)
        loop.pause()
        loop.tick()
        loop.run()
        plant = SandboxPlant.on_loop(loop, commands, 1.0, None)
        assert plant.readings() is None  # no sensors asked for
        plant.use_sensors(SensingConfig(distance=DistanceSensorConfig()))
        assert np.isnan(plant.readings().distances).all()  # before the first step, as rps 2.0
        for _ in range(3):
            plant.apply(np.tile([0.1, 0.0], (3, 1)))
        sensed = plant.readings()
        assert sensed.distances.shape == (3, 7) and not np.isnan(sensed.distances).any()
        assert np.abs(sensed.encoders).sum() > 0  # the wheels turned as the loop commanded them
    finally:
        loop.close()


def test_the_portal_builds_its_loop_with_the_scripts_obstacles():
    from swarmdeck.console.runtime.loop import LoopConfig
    from swarmdeck.console.sandbox.plant import script_obstacles_config
    from swarmdeck.core.obstacles import ObstacleError, Obstacles

    lab = LoopConfig(n_robots=3, obstacles=Obstacles([[[1.2, -0.5], [1.2, 0.5]]]))
    config = script_obstacles_config(lab, [[[1.0, -0.5], [1.0, 0.5]]], POSES)
    assert config.obstacles.m == 2 and lab.obstacles.m == 1  # the lab's and the script's; the lab's config unchanged
    with pytest.raises(ObstacleError, match="segment 1 .*start pose 1"):
        script_obstacles_config(lab, [[[0.0, -0.3], [0.0, 0.3]]], POSES)
    with pytest.raises(ObstacleError, match="outside the arena"):
        script_obstacles_config(lab, [[[5.0, 0.0], [6.0, 0.0]]], POSES)
