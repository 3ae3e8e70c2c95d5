"""The firmware model of the simulated fleet on a virtual clock: newest command, 500 ms brake, battery."""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core.kinematics import GritsBotParams, unicycle_step
from swarmdeck.devices.battery import BatteryParams
from swarmdeck.devices.net.firmware import FirmwareParams, FleetState


def straight_fleet(n: int = 1) -> FleetState:
    poses = np.column_stack((np.arange(n) * 0.5, np.zeros(n), np.zeros(n)))
    return FleetState(np.arange(n), poses, 0.0)


def run(fleet: FleetState, t_end: float, period: float) -> None:
    for t in np.arange(period, t_end + 1e-12, period):
        fleet.advance(float(t))


def test_single_command_moves_exactly_half_a_second():
    fleet = straight_fleet()
    fleet.receive([0], [0.1], [0.0], [0.0123])
    run(fleet, 2.0, 0.016)
    assert np.isclose(fleet.poses[0, 0], 0.1 * 0.5, atol=1e-12)
    assert fleet.timeouts[0] == 1
    v, w = fleet.applied()
    assert v[0] == 0 and w[0] == 0


@settings(max_examples=40, deadline=None)
@given(
    gaps=st.lists(st.floats(0.14, 0.9), min_size=1, max_size=8),  # > loop period: each command sees a tick
    speeds=st.lists(st.floats(-0.2, 0.2, allow_subnormal=False), min_size=8, max_size=8),
    turns=st.lists(st.floats(-2.0, 2.0, allow_subnormal=False), min_size=8, max_size=8),
    period=st.sampled_from([0.016, 0.05, 0.13]),
)
def test_piecewise_motion_matches_closed_form(gaps, speeds, turns, period):
    """Each command acts from its receive time until the next one or +0.5 s, whatever the loop period."""
    params = GritsBotParams()
    times = np.cumsum(gaps)
    fleet = FleetState([0], np.zeros((1, 3)), 0.0, params=params)
    expected = np.zeros((1, 3))
    t = 0.0
    for k, tc in enumerate(times):
        # loop ticks up to the arrival of command k
        while t + period < tc:
            t += period
            fleet.advance(t)
        fleet.receive([0], [speeds[k]], [turns[k]], [tc])
    t_end = times[-1] + 1.0
    while t < t_end:
        t += period
        fleet.advance(t)
    # closed form: piecewise arcs
    for k, tc in enumerate(times):
        nxt = times[k + 1] if k + 1 < len(times) else np.inf
        tau = min(nxt - tc, 0.5)
        v, w = speeds[k], turns[k]
        # wheel limits scale (v, w) uniformly
        from swarmdeck.core.kinematics import limit_unicycle

        lv, lw, _ = limit_unicycle(np.array([v]), np.array([w]), params)
        expected = unicycle_step(expected, lv * tau, lw * tau, 1.0)
    assert np.allclose(fleet.poses[:, :2], expected[:, :2], atol=1e-9)
    assert np.isclose(np.cos(fleet.poses[0, 2] - expected[0, 2]), 1.0)


def test_commands_superseded_within_one_loop_are_never_applied():
    fleet = straight_fleet()
    fleet.advance(0.016)
    fleet.receive([0], [0.2], [0.0], [0.020])
    fleet.receive([0], [0.1], [0.0], [0.025])  # newer, before the next loop tick
    fleet.advance(0.032)
    assert np.isclose(fleet.poses[0, 0], 0.1 * (0.032 - 0.025))


def test_newest_command_wins_and_older_ones_are_ignored():
    fleet = straight_fleet()
    fleet.receive([0], [0.2], [0.0], [0.10])
    fleet.receive([0], [0.05], [0.0], [0.05])  # arrived later but stamped earlier: out of order
    fleet.advance(0.2)
    assert np.isclose(fleet.poses[0, 0], 0.2 * 0.1)


def test_battery_drains_faster_when_driving():
    b = BatteryParams()
    fleet = straight_fleet(2)
    for k in range(100):
        t = k * 0.033
        fleet.receive([0], [0.2], [0.0], [t])
        fleet.advance(t + 0.033)
    volts = fleet.battery_voltage()
    assert volts[0] < volts[1] < b.full_voltage
    idle_drop = b.idle_current * fleet.t / 3600 / b.capacity_ah * (b.full_voltage - b.empty_voltage)
    assert np.isclose(b.full_voltage - volts[1], idle_drop)


def test_rejects_duplicate_ids():
    import pytest

    with pytest.raises(ValueError, match="distinct"):
        FleetState([1, 1], np.zeros((2, 3)))
    with pytest.raises(ValueError, match="positive"):
        FirmwareParams(command_timeout=0)
