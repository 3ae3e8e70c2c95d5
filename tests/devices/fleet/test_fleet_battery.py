"""The battery: CC-CV charging curve on the chargers, drain while driving (the firmware's model)."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.devices.fleet import BatteryParams, battery_step, charge_from_voltage, recharge
from swarmdeck.devices.net.firmware import FleetState

B = BatteryParams()


def test_constant_current_phase_is_linear_in_time():
    # 0.5 A into 1 Ah: 0.5/3600 of the capacity per second
    q = recharge(np.array([0.1, 0.5]), 360.0, B)
    assert np.allclose(q, [0.1 + 0.05, 0.5 + 0.05])


def test_constant_voltage_phase_closes_the_gap_exponentially():
    tau = 3600.0 * B.capacity_ah * (1 - B.cv_start) / B.charge_current  # 1440 s
    q = recharge(np.array([B.cv_start, 0.9]), tau, B)
    assert np.allclose(1 - q, np.array([1 - B.cv_start, 0.1]) * np.exp(-1.0))


def test_an_empty_battery_charges_fully_in_about_two_and_a_half_hours():
    t_cc = 3600.0 * B.cv_start / B.charge_current
    q = recharge(np.zeros(1), t_cc, B)
    assert np.allclose(q, B.cv_start)
    assert recharge(np.zeros(1), t_cc + 5 * 1440.0, B)[0] > 0.998
    assert recharge(np.ones(1), 1e6, B)[0] == 1.0


@settings(max_examples=30)
@given(q0=st.floats(0.0, 1.0), dt=st.floats(0.0, 5000.0), k=st.integers(1, 20))
def test_charging_in_pieces_equals_charging_at_once_and_never_passes_full(q0, dt, k):
    once = recharge(np.array([q0]), dt, B)
    q = np.array([q0])
    for _ in range(k):
        q = recharge(q, dt / k, B)
    assert np.allclose(q, once, atol=1e-12)
    assert q0 - 1e-15 <= once[0] <= 1.0


def test_docked_robots_charge_and_driving_robots_drain_as_the_firmware_model_does():
    robot = GritsBotParams()
    q0 = np.array([0.6, 0.6, 0.6])
    v, w = np.array([0.0, 0.1, 0.2]), np.array([0.0, 1.0, 0.0])
    q = battery_step(q0, 10.0, v, w, np.array([True, False, False]), robot, B)
    assert q[0] > 0.6 > q[1] and q[2] < q[1] < 0.6
    fleet = FleetState([0, 1, 2], np.zeros((3, 3)), 0.0, battery=B, charge=0.6)
    fleet.receive([1, 2], v[1:], w[1:], 0.0)
    for t in np.arange(0.4, 10.01, 0.4):  # commands renewed within the 500 ms brake
        fleet.advance(t)
        fleet.receive([1, 2], v[1:], w[1:], t)
    assert np.allclose(fleet.charge[1:], q[1:], rtol=0, atol=1e-12)


def test_voltage_and_charge_are_inverse_and_nan_stays_unknown():
    q = np.array([0.0, 0.25, 1.0, np.nan])
    back = charge_from_voltage(B.voltage(q), B)
    assert np.allclose(back[:3], q[:3]) and np.isnan(back[3])
