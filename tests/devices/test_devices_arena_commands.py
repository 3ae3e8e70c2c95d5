"""The experiment API's command path: bad commands stop robots and are reported; inputs never mutated."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.devices import Arena


def _arena(n=4, safety=False, **kw):
    poses = np.column_stack((np.linspace(-1.0, 1.0, n), np.zeros(n), np.zeros(n)))
    return Arena(initial_conditions=poses, safety=safety, **kw)


def test_nan_command_stops_that_robot_and_the_report_counts_it():
    arena = _arena()
    u = np.full((4, 2), 0.1)
    u[1] = np.nan
    before = arena.poses()
    for _ in range(3):
        arena.set_velocities(u)
        arena.step()
    after = arena.poses()
    assert np.allclose(after[1], before[1])  # stopped
    assert not np.allclose(after[0], before[0])  # the others moved
    report = arena.report()
    assert report.to_dict()["invalid_commands"] == 3
    assert "invalid (NaN/inf) commands stopped: 3 robot-steps" in str(report)


def test_filter_returning_garbage_stops_every_robot():
    class Broken:
        def filter(self, points, nominal, obstacles=None):
            return np.full_like(nominal, np.nan), None

    arena = _arena(safety=Broken())
    before = arena.poses()
    arena.set_velocities(np.full((4, 2), 0.1))
    arena.step()
    assert np.array_equal(arena.poses(), before)
    assert arena.report().safety.failures == 1


def test_events_are_bounded():
    arena = _arena(n=2)
    arena.set_velocities(np.full((2, 2), np.inf))
    for _ in range(500):
        arena.step()
    assert arena.invalid_commands == 1000 and len(arena.events) <= 200


@settings(max_examples=40, deadline=None)
@given(rows=st.integers(0, 6), cols=st.integers(0, 4))
def test_wrong_shapes_name_the_argument_and_shape(rows, cols):
    arena = _arena()
    if (rows, cols) == (4, 2):
        return
    with pytest.raises(ValueError, match=r"velocities must have shape \(4, 2\)"):
        arena.set_velocities(np.zeros((rows, cols)))


def test_caller_arrays_are_never_modified():
    arena = _arena()
    u = np.full((4, 2), 0.1)
    u[2] = np.nan
    goals = np.array([[0.5, 0.5], [0.1, 0.2], [-0.5, 0.0], [0.0, -0.5]])
    copies = u.copy(), goals.copy()
    arena.set_velocities(u)
    arena.step()
    arena.set_goals(goals)
    arena.step()
    assert np.array_equal(u, copies[0], equal_nan=True) and np.array_equal(goals, copies[1])


def test_waypoints_for_a_subset_of_robots():
    arena = _arena(n=3)
    start = arena.positions()
    arena.set_waypoints([start[0:1] + [0.1, 0.1], start[2:3] + [[0.0, 0.1], [0.1, 0.1]]], ids=[0, 2])
    for _ in range(200):
        arena.step()
    p = arena.positions()
    assert np.linalg.norm(p[0] - (start[0] + [0.1, 0.1])) < 0.03
    assert np.linalg.norm(p[1] - start[1]) < 1e-3  # not named: holds
    assert np.linalg.norm(p[2] - (start[2] + [0.1, 0.1])) < 0.03 and arena.waypoint_index[2] == 1
    arena.set_waypoints([start[1:2] + [-0.1, 0.0]], ids=[1])  # the others keep their lists
    for _ in range(200):
        arena.step()
    p = arena.positions()
    assert np.linalg.norm(p[1] - (start[1] + [-0.1, 0.0])) < 0.03
    assert np.linalg.norm(p[2] - (start[2] + [0.1, 0.1])) < 0.03 and arena.waypoint_index[2] == 1
    with pytest.raises(ValueError, match=r"one \(K_i, 2\) array per robot in ids \(2\)"):
        arena.set_waypoints([start[0:1]], ids=[0, 1])


@pytest.mark.parametrize("bad", [3, 3.5, "abc", [np.zeros((1, 2), dtype=complex)] * 4, [[["a", "b"]]] * 4,
                                 [np.array([[0.0, np.nan]])] * 4, [np.zeros((0, 2))] * 4])
def test_bad_waypoints_are_value_errors(bad):
    with pytest.raises(ValueError, match="waypoints"):
        _arena().set_waypoints(bad)


def test_waypoints_copied_from_the_caller():
    arena = _arena(n=1)
    wps = np.array([[0.3, 0.2]])
    arena.set_waypoints([wps])
    wps[0] = [5.0, 5.0]
    for _ in range(400):
        arena.step()
    assert np.linalg.norm(arena.positions()[0] - [0.3, 0.2]) < 0.03


def test_round_off_is_not_counted_as_an_intervention():
    class RoundTrip:  # returns the nominal through a lossy float round trip, changes nothing really
        def filter(self, points, nominal, obstacles=None):
            return (np.asarray(nominal) * 3.0) / 3.0 + 1e-17, None

    arena = _arena(safety=RoundTrip())
    for _ in range(20):
        arena.set_unicycle(np.full(4, 0.1), np.full(4, 0.7))
        arena.step()
    assert arena.report().safety.interventions == 0


@pytest.mark.parametrize("safety", [False, True])
def test_commands_scaled_to_the_wheel_limits_are_reported(safety):
    arena = _arena(safety=safety)
    for _ in range(5):
        arena.set_unicycle(np.full(4, 1.0), np.zeros(4))  # 1 m/s: five times what the wheels can do
        arena.step()
    report = arena.report()
    assert report.to_dict()["safety"]["saturations"] == 20 and report.to_dict()["safety"]["saturation_steps"] == 5
    assert "commands scaled down to the wheel limits: 20 robot-steps in 5 steps" in str(report)
