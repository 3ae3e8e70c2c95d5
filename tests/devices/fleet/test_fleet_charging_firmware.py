"""The simulated firmware charges robots docked on the charging strips and drains the others (virtual clock)."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.devices.fleet import BatteryParams, ChargerLayout, recharge
from swarmdeck.devices.net.firmware import FleetState


def test_docked_robots_charge_by_the_cc_cv_curve_and_report_it_moving_ones_drain():
    layout = ChargerLayout()
    docks = layout.dock_poses()
    poses = np.vstack((docks[[0, 20]], [[0.0, 0.0, 0.0]]))
    st = FleetState([0, 1, 2], poses, 0.0, charge=0.3, chargers=layout)
    assert st.charging().tolist() == [True, True, False]
    st.receive([1, 2], [0.1, 0.1], [0.0, 0.0], 0.0)  # robot 1 drives off its slot, robot 2 drives on the floor
    for k in range(1, 61):  # 60 s in 0.4 s steps, commands renewed within the 500 ms brake
        st.receive([1, 2], [0.1 * (k < 3), 0.1], [0.0, 0.0], 0.4 * k - 0.05)
        st.advance(0.4 * k)
    assert st.charging().tolist() == [True, False, False]
    expected = np.array([0.3])
    for _ in range(60):
        expected = recharge(expected, 0.4, BatteryParams())
    assert st.charge[0] == pytest.approx(expected[0], abs=1e-12)  # exact CC-CV, step by step
    assert st.charge[0] > 0.3 and st.charge[1] < 0.3 and st.charge[2] < st.charge[1]  # driving drains more
    v = st.battery_voltage()
    assert v[0] > v[1] > v[2]


def test_without_chargers_nobody_charges_and_bad_charge_is_refused():
    st = FleetState([0], ChargerLayout().dock_poses()[:1], 0.0, charge=0.5)
    st.advance(10.0)
    assert not st.charging().any() and st.charge[0] < 0.5
    with pytest.raises(ValueError, match=r"charge must be in \[0, 1\]"):
        FleetState([0], [[0.0, 0.0, 0.0]], charge=np.nan)
