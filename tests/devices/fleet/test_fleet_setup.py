"""Setup from the chargers: every robot reaches its start pose (2 cm, 5 deg), no collision, bad input named."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core.kinematics import wrap_angle
from swarmdeck.devices.fleet import AssignmentError, FleetManager, SetupFailed
from swarmdeck.devices.fleet.setup import ACCEPT_HEADING, ACCEPT_POSITION
from swarmdeck.devices.initial_conditions import random_initial_poses
from swarmdeck.devices.simulator import ArenaConfig


def set_up(n: int, seed: int):
    fleet = FleetManager(n, config=ArenaConfig(seed=seed))  # docked on n random slots of the 50
    goals = random_initial_poses(n, fleet.config.bounds, rng=seed + 1)
    report = fleet.setup(goals)
    return fleet, goals, report


def assert_at_start(fleet, goals, report):
    assert report.ok and report.not_at_pose == []
    assert report.collision_steps == 0 and fleet.sim.report.steps_with_collision == 0
    assert fleet.sim.report.steps_with_boundary == 0
    p = fleet.poses()[fleet.assignment.rows]  # experiment robot k is fleet row rows[k]
    assert np.all(np.hypot(*(p[:, :2] - goals[:, :2]).T) <= ACCEPT_POSITION)
    assert np.all(np.abs(wrap_angle(p[:, 2] - goals[:, 2])) <= ACCEPT_HEADING)
    assert report.max_position_error <= ACCEPT_POSITION and report.max_heading_error <= ACCEPT_HEADING


@settings(max_examples=4)
@given(n=st.integers(2, 20), seed=st.integers(0, 10_000))
def test_setup_from_random_docks_to_random_start_poses_always_finishes(n, seed):
    assert_at_start(*set_up(n, seed))


@pytest.mark.parametrize("n, seed", [(50, 7), (50, 11), (35, 3)])
def test_a_full_or_crowded_arena_from_the_chargers_to_random_start_poses(n, seed):
    fleet, goals, report = set_up(n, seed)
    assert_at_start(fleet, goals, report)
    assert fleet.ready() and fleet.docked().sum() == 0


def test_robots_left_on_the_chargers_are_obstacles_and_start_poses_near_them_are_refused():
    fleet = FleetManager(config=ArenaConfig(seed=3))  # 50 robots, one per slot
    d10, d11 = fleet.poses()[10], fleet.poses()[11]  # neighbours on the bottom wall
    between = (d10[:2] + d11[:2]) / 2 + [0.0, 0.16]  # one of them is assigned, the other stays docked
    near = np.array([[between[0], between[1], 0.0], [0.0, 0.0, 0.0]])
    with pytest.raises(ValueError, match=r"start pose 0 .* from robot \d+ docked on charger slot \d+ \(it stays there\)"):
        fleet.setup(near)
    goals = np.array([[-0.5, 0.0, 0.0], [0.5, 0.0, np.pi], [0.0, 0.3, 1.0]])
    report = fleet.setup(goals)
    assert report.ok and fleet.sim.report.steps_with_collision == 0
    exp = fleet.experiment()
    assert exp.n_robots == 3 and exp.obstacles().shape == (47, 2)


@pytest.mark.parametrize("goals, match", [
    ([[1.58, 0.0, 0.0], [0.0, 0.0, 0.0]], r"start pose 0 \(1\.580, 0\.000, 0\.000\) is outside the arena"),
    ([[0.0, 0.0, 0.0], [0.2, 0.0, 0.0]], r"start poses 0 and 1 are 0\.200 m apart, closer than the safety distance 0\.230 m"),
    ([[0, 0, 0], [1, 0, 0]], "must be a float array"),
])
def test_bad_start_poses_are_named(goals, match):
    fleet = FleetManager(4, config=ArenaConfig(seed=0))
    with pytest.raises(ValueError, match=match):
        fleet.setup(np.array(goals))
    assert fleet.assignment is None and fleet.docked().all()


def test_more_robots_than_charged_robots_names_them():
    fleet = FleetManager(4, config=ArenaConfig(seed=0), charge=[0.9, 0.3, np.nan, 0.95])
    goals = random_initial_poses(3, fleet.config.bounds, rng=1)
    with pytest.raises(AssignmentError, match=r"needs 3 robots but only 2.*robot 1: battery 30% < 50%.*robot 2: battery reads NaN"):
        fleet.setup(goals)
    report = fleet.setup(goals[:2])
    assert sorted(fleet.assignment.ids.tolist()) == [0, 3]  # never the low or unknown battery
    assert report.ok


def test_a_setup_that_cannot_finish_in_time_stops_the_robots_and_names_them():
    fleet = FleetManager(3, config=ArenaConfig(seed=0))
    goals = random_initial_poses(3, fleet.config.bounds, rng=5)
    with pytest.raises(SetupFailed, match=r"setup did not finish within 2 s: robot \d+ [\d.]+ cm / [\d.]+ deg away") as err:
        fleet.setup(goals, time_limit=2.0)
    assert len(err.value.report.not_at_pose) >= 1 and not err.value.report.ok
    v, w = fleet.sim.applied
    assert np.all(v == 0) and np.all(w == 0)
