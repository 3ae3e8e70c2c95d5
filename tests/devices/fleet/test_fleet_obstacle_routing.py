"""Setup and return round line-segment obstacles: a start pose behind a wall segment is reached (the maneuver
routes round the wall instead of stalling against it), the robots go back to their chargers the same way,
nobody touches the wall, and a segment over a charger slot or a start pose is refused naming both."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.core.obstacles import ObstacleError, Obstacles, point_segment_distance
from swarmdeck.devices.chargers import ChargerLayout
from swarmdeck.devices.fleet import FleetManager
from swarmdeck.devices.fleet.manager import FleetConfig
from swarmdeck.devices.fleet.routing import Router, clear_paths
from swarmdeck.devices.fleet.setup import ACCEPT_POSITION
from swarmdeck.devices.simulator import ArenaConfig

# a wall across most of the arena, between the bottom chargers and the start poses above it
WALL = Obstacles([[[-1.2, 0.0], [1.2, 0.0]]])


def _fleet(n: int, obstacles: Obstacles = WALL) -> FleetManager:
    cfg = ArenaConfig(seed=2, obstacles=obstacles)
    layout = ChargerLayout(bounds=cfg.bounds, walls=("bottom",))
    return FleetManager(n, config=cfg, fleet=FleetConfig(layout=layout))


def test_router_goes_round_the_end_of_the_wall() -> None:
    router = Router(WALL, ArenaConfig().bounds)
    plan = router.for_goals(np.array([[0.0, 0.5]]))
    wp, length = plan.waypoints(np.array([[0.0, -0.5]]))
    assert abs(abs(wp[0, 0]) - 1.2) < 0.3 and abs(wp[0, 1]) < 0.3  # a corner at one end of the wall
    assert length[0] > 2.4  # round the wall, not through it
    assert clear_paths(np.array([[0.0, -0.5]]), wp, WALL.segments, 0.1, from_robot=True)[0]
    wp, length = plan.waypoints(np.array([[0.3, 0.6]]))  # in sight of the goal: straight there
    np.testing.assert_allclose(wp, [[0.0, 0.5]])


def test_setup_behind_a_wall_and_return_to_the_chargers() -> None:
    fleet = _fleet(3)
    goals = np.array([[-0.5, 0.5, 0.0], [0.0, 0.6, 1.0], [0.5, 0.5, 2.0]])
    report = fleet.setup(goals)
    assert report.ok, report
    p = fleet.poses()[fleet.assignment.rows]
    assert np.all(np.hypot(*(p[:, :2] - goals[:, :2]).T) <= ACCEPT_POSITION)
    assert fleet.sim.report.steps_with_obstacle_contact == 0 and fleet.sim.report.steps_with_collision == 0
    back = fleet.return_to_chargers()
    assert back.ok, back
    assert fleet.docked().all()
    assert fleet.sim.report.steps_with_obstacle_contact == 0 and fleet.sim.report.steps_with_collision == 0


def test_a_segment_over_a_charger_slot_is_refused() -> None:
    with pytest.raises(ObstacleError, match=r"segment 0 .*crosses charger slot \d+"):
        _fleet(2, Obstacles([[[-0.5, -0.95], [0.5, -0.95]]]))


def test_a_segment_over_a_chargers_approach_pose_is_refused() -> None:
    # 9 cm in front of the approach poses: a returning robot could not turn there to reverse onto its slot
    with pytest.raises(ObstacleError, match=r"segment 0 .*crosses the approach pose of charger slot \d+"):
        _fleet(2, Obstacles([[[-1.0, -0.45], [1.0, -0.45]]]))


def test_a_start_pose_on_a_segment_is_refused() -> None:
    fleet = _fleet(2)
    with pytest.raises(ObstacleError, match=r"segment 0 .*crosses start pose 1"):
        fleet.setup(np.array([[0.0, 0.5, 0.0], [0.3, 0.05, 0.0]]))


def test_arena_from_docks_sets_up_behind_a_wall() -> None:
    from swarmdeck.devices import Arena

    obs = Obstacles([[[-1.0, -0.4], [1.0, -0.4]]])
    arena = Arena(initial_conditions=np.array([[-0.3, 0.2, 0.0], [0.3, 0.2, 0.0]]), obstacles=obs,
                  from_docks=True, config=ArenaConfig(seed=1))
    assert point_segment_distance(arena.poses()[:, :2], obs.segments).min() > 0.1
    assert np.all(np.hypot(*(arena.poses()[:, :2] - [[-0.3, 0.2], [0.3, 0.2]]).T) <= ACCEPT_POSITION)
