"""Batteries live: the simulated MQTT fleet (real mosquitto) reports batt_volt/charge_status, docked robots
charging; every Frame carries them, the loop warns about the robot low on battery off the charger (by id),
the Batteries panel lists it first and the scene draws a bar per robot coloured by level."""
from __future__ import annotations

import json
import time

import numpy as np
import pytest
from mqtt_broker import wait_until

from swarmdeck.console.recording.codec import decode_frame, encode_frame
from swarmdeck.console.runtime.batteries import BatteryWatch, battery_levels, low_battery_alert
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.hardware import mqtt_robots
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.web.battery_panel import battery_table
from swarmdeck.console.web.scene import BATTERY_COLORS, battery_bars
from swarmdeck.devices.fleet import BatteryParams, ChargerLayout
from swarmdeck.devices.net.fleet import FleetNode
from swarmdeck.devices.net.mqtt_config import parse_broker_url

pytestmark = pytest.mark.mqtt


def test_console_shows_and_warns_about_the_fleets_batteries(mosquitto):
    layout = ChargerLayout()
    poses = np.vstack((layout.dock_poses()[[0, 1]], [[0.0, 0.0, 0.0], [0.6, 0.3, 1.0]]))
    charge = np.array([0.2, 0.9, 0.2, 0.9])  # robot 0 low but charging; robot 2 low on the floor
    fleet = FleetNode(parse_broker_url(mosquitto.url), [0, 1, 2, 3], poses, chargers=layout, charge=charge,
                      name="fleet-batteries").start()
    loop = None
    try:
        sink, source = mqtt_robots(mosquitto.url, np.arange(4), wait_for_poses=15)
        loop = ControlLoop(LoopConfig(n_robots=4), source=source, sink=sink, clock=time.monotonic)
        loop.pause()  # robots stay where they are (docked ones keep charging)
        # the status messages (1 s period) bring charge_status; the pose topic brings batt_volt at 30 Hz
        frame = wait_until(lambda: (f := loop.tick()).charging[:2].all() and np.isfinite(f.battery).all() and f,
                           20, "battery and charging reports in a Frame")
    finally:
        if loop is not None:
            loop.close()
        fleet.stop()
    volts = BatteryParams().voltage(charge)
    np.testing.assert_allclose(frame.battery, volts, atol=2e-3)  # the wire rounds to mV; the robots idle a little
    assert frame.charging.tolist() == [True, True, False, False]
    assert any("battery low" in a and "robot(s) 2;" in a for a in frame.alerts)  # 0 is low too, but charging
    table = battery_table(frame)
    assert "robot(s) 2" in table.splitlines()[0] and "| 2 | 3.48 | 20% | 🔴 low |" in table
    assert table.index("| 2 |") < table.index("| 0 |")  # low robots first
    segs, cols = battery_bars(frame, 0.055)
    assert segs.shape == (8, 2, 3)
    _, level = battery_levels(frame.battery, frame.charging)
    assert (cols[4:, 0] == BATTERY_COLORS[level]).all()
    assert (cols[4, 0] == BATTERY_COLORS[4]).all() and (cols[6, 0] == BATTERY_COLORS[1]).all()  # charging, low
    # recorded: exactly in frame format 1, as float32 volts in the compact format 2
    one = Frame.from_dict(json.loads(json.dumps(frame.to_dict())))
    assert np.array_equal(one.battery, frame.battery) and np.array_equal(one.charging, frame.charging)
    two = decode_frame(encode_frame(frame))
    np.testing.assert_allclose(two.battery, frame.battery, rtol=1e-7)
    assert np.array_equal(two.charging, frame.charging) and not two.is_virtual.any()


def test_levels_alert_and_table_from_plain_arrays():
    watch = BatteryWatch()
    volts = np.array([np.nan, 3.3, 3.6, 4.0, 3.4])
    q, level = battery_levels(volts, np.array([False, False, False, False, True]), watch)
    assert np.isnan(q[0]) and level.tolist() == [0, 1, 2, 3, 4]
    assert low_battery_alert(np.array([7, 8, 9, 10, 11]), volts, np.zeros(5, bool)) == (
        "battery low (< 25%): robot(s) 8, 11; return them to the chargers")
    assert low_battery_alert(np.array([1]), np.array([np.nan]), np.zeros(1, bool)) is None
    with pytest.raises(ValueError, match="warn_below"):
        BatteryWatch(warn_below=1.5)
