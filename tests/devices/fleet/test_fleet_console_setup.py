"""Setting robots up through the console's loop (the same safety pipeline as every behaviour): charged robots
are assigned, reach their start poses within 2 cm and 5°, docked robots are never pushed off their strip;
bad start poses and too few charged robots are refused by name."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.console.runtime import fleet_upkeep as fu
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.devices import ArenaConfig
from swarmdeck.devices.fleet import AssignmentError, ChargerLayout
from swarmdeck.devices.simulated_robots import SimulatedRobots

CHARGERS = ChargerLayout()


def _docked_loop(n: int, charge=1.0) -> ControlLoop:
    sim = SimulatedRobots(n, ArenaConfig(seed=1), chargers=CHARGERS, start_docked=True, charge=charge)
    loop = ControlLoop(LoopConfig(n_robots=n), source=sim, sink=sim)
    loop.pause()
    return loop


def test_set_up_assigns_charged_robots_and_leaves_the_others_docked():
    charge = np.array([0.9, 0.2, 0.9, 0.9, 0.9, 0.9])  # robot 1 is low: never picked
    loop = _docked_loop(6, charge)
    frame = loop.tick()
    goals = np.array([[-1.0, -0.4, 0.0], [-0.6, -0.3, 1.2], [-0.2, -0.5, -2.0]])
    m = fu.set_up(fu.FleetView.of(frame), goals, frame.bounds, CHARGERS)
    assert 1 not in m.ids.tolist() and len(m.ids) == 3
    staying = np.setdiff1d(frame.ids, m.ids)
    before = frame.poses[staying].copy()
    result = fu.run_maneuver(loop, m)
    loop.close()
    assert result.ok and result.collisions == 0, result.message
    assert result.max_position_error <= fu.ACCEPT_POSITION and result.max_heading_error <= fu.ACCEPT_HEADING
    last = loop.latest
    rows = [int(np.flatnonzero(last.ids == i)[0]) for i in m.ids]
    np.testing.assert_allclose(last.poses[rows, :2], goals[:, :2], atol=0.02)
    assert np.array_equal(last.poses[staying], before)  # fixed obstacles: not nudged a micrometre
    assert last.charging[staying].all()
    assert "set up: done" in m.health() and "3 robot(s)" in m.health()


def test_bad_start_poses_and_too_few_charged_robots_are_named():
    loop = _docked_loop(4, np.array([0.9, 0.9, np.nan, 0.1]))
    frame = loop.tick()
    loop.close()
    view = fu.FleetView.of(frame)
    with pytest.raises(ValueError, match=r"start pose 1 \(2\.000, 0\.000, 0\.000\) is outside the arena"):
        fu.set_up(view, [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]], frame.bounds, CHARGERS)
    with pytest.raises(ValueError, match="start poses 0 and 1 are 0.100 m apart"):
        fu.set_up(view, [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]], frame.bounds, CHARGERS)
    with pytest.raises(ValueError, match=r"robot 3 \(staying\)"):  # a start pose on low robot 3, which stays docked
        fu.set_up(view, [CHARGERS.dock_poses()[3] + [0.0, 0.12, 0.0]], frame.bounds, CHARGERS)
    three = [[-0.5, 0.0, 0.0], [0.0, 0.0, 0.0], [0.5, 0.0, 0.0]]
    with pytest.raises(AssignmentError, match=r"robot 2: battery reads NaN; robot 3: battery 10% < 50%"):
        fu.set_up(view, three, frame.bounds, CHARGERS)
    with pytest.raises(ValueError, match="5 start poses but only 4 robots"):
        fu.set_up(view, [[x, 0.0, 0.0] for x in (-1.0, -0.5, 0.0, 0.5, 1.0)], frame.bounds, CHARGERS)


@pytest.mark.parametrize("text, message", [
    ("x,y,theta\n0,0\n", "line 2: expected 3 values"),
    ("0,0,zero\n", "line 1: not numbers"),
    ("0,nan,0\n", "line 1: x, y, theta must be finite"),
    ("# only a comment\n", "no start poses"),
])
def test_malformed_pose_files_name_the_line(text, message):
    with pytest.raises(ValueError, match=message):
        fu.read_poses_csv(text=text)
    assert fu.read_poses_csv(text="x, y, theta\n# robot 0\n0.5, -0.25, 1.5\n").tolist() == [[0.5, -0.25, 1.5]]


def test_a_setup_that_cannot_finish_stops_the_robots_and_names_them():
    loop = _docked_loop(2)
    frame = loop.tick()
    m = fu.set_up(fu.FleetView.of(frame), [[0.5, 0.5, 0.0]], frame.bounds, CHARGERS, config=fu.UpkeepConfig(time_limit=1.0))
    result = fu.run_maneuver(loop, m)
    assert not result.ok and m.state == "failed"
    assert "did not finish within 1 s: robot" in result.message and "every robot stopped" in result.message
    frame = loop.tick()
    assert frame.stopped and any("did not finish" in a for a in frame.alerts)
    loop.close()


def test_mqtt_robots_without_a_battery_reading_are_never_assigned_simulated_ones_count_as_full():
    loop = ControlLoop(LoopConfig(n_robots=3, seed=2))  # a plain simulation: no battery model
    frame = loop.tick()
    loop.close()
    one = [[0.0, 0.0, 0.0]]
    assert len(fu.set_up(fu.FleetView.of(frame), one, frame.bounds, CHARGERS).ids) == 1
    # the same robots as MQTT robots (firmware heard from just now) that never sent a valid batt_volt
    with pytest.raises(AssignmentError, match=r"robot 0: battery reads NaN; robot 1: battery reads NaN"):
        fu.set_up(fu.FleetView.of(frame, np.zeros(3)), one, frame.bounds, CHARGERS)
