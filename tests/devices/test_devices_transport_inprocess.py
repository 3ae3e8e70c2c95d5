"""The in-process transport: the default path, bit-identical to driving the simulated arena directly."""
from __future__ import annotations

import numpy as np

from swarmdeck.core.kinematics import unicycle_to_wheels
from swarmdeck.core.ports import CommandSink, PoseSource
from swarmdeck.devices import Arena, ArenaConfig, SimulatedArena
from swarmdeck.devices.net.console_robots import NetworkRobots
from swarmdeck.devices.net.transport import PoseFeed, RobotTransport
from swarmdeck.devices.net.transport_inprocess import InProcessTransport


def backend_on_transport(n: int, seed: int) -> tuple[NetworkRobots, InProcessTransport]:
    transport = InProcessTransport(SimulatedArena(n, config=ArenaConfig(seed=seed)))
    backend = NetworkRobots(transport, np.arange(n), background=False, clock=lambda: transport.time,
                            simulated_time=True)
    return backend, transport


def test_protocols_are_satisfied():
    backend, transport = backend_on_transport(3, 1)
    assert isinstance(transport, RobotTransport) and isinstance(transport, PoseFeed)
    assert isinstance(backend, PoseSource) and isinstance(backend, CommandSink)


def test_arena_through_the_transport_matches_the_direct_simulation():
    n, seed = 5, 8
    direct = Arena(n, config=ArenaConfig(seed=seed), safety=False)
    backend, transport = backend_on_transport(n, seed)
    via = Arena(backend=backend, config=ArenaConfig(seed=seed), safety=False)
    assert np.array_equal(direct.poses(), via.poses())
    goals = np.random.default_rng(3).uniform([-1.2, -0.7], [1.2, 0.7], (n, 2))
    for arena in (direct, via):
        arena.set_goals(goals, controller="clf")
    for _ in range(90):
        direct.step()
        via.step()
    assert np.array_equal(direct.poses(), via.poses())
    assert backend.streamer.counters.get("stale_pose_robot_ticks") == 0
    assert transport.status().counters["commands_sent"] == 90 * n


def test_robots_not_named_stand_still_and_status_reports_batteries():
    transport = InProcessTransport(SimulatedArena(3, config=ArenaConfig(seed=4)))
    before = transport.latest_poses().poses
    for _ in range(30):
        assert transport.send([1], [0.2], [0.0])
    after = transport.latest_poses().poses
    assert np.array_equal(after[[0, 2]], before[[0, 2]])
    assert np.isclose(np.linalg.norm(after[1, :2] - before[1, :2]), 0.2 * 30 * 0.033)
    st = transport.status()
    assert st.connected and st.robots.link == ("ok", "ok", "ok")
    assert st.robots.battery_voltage[1] < st.robots.battery_voltage[0] < 4.2
    assert st.robots.command_age[1] == 0 and np.isinf(st.robots.command_age[0])
    transport.close()
    assert transport.send([1], [0.2], [0.0]) is False


def test_backend_applies_wheel_limits_before_sending():
    backend, _ = backend_on_transport(2, 6)
    v, w = np.array([1.0, 0.1]), np.array([4.0, np.nan])
    backend.send(np.arange(2), v, w)
    sent = backend.streamer.last_tick
    right, left = unicycle_to_wheels(sent.v, sent.w, backend.params)
    assert np.all(np.maximum(np.abs(right), np.abs(left)) <= backend.params.max_wheel_speed + 1e-9)
    assert np.isclose(sent.w[0] / sent.v[0], 4.0)  # curvature kept
    assert sent.v[1] == 0.0 and sent.w[1] == 0.0  # NaN sent as zero
    assert backend.saturated == 1 and backend.invalid == 1
    assert np.array_equal(v, [1.0, 0.1])  # caller's arrays untouched
