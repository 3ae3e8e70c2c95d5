"""Charging strips: slots fit the arena and its robots, larger arenas get more, bad layouts are named."""
import numpy as np
import pytest

from swarmdeck.core.kinematics import GritsBotParams, lookahead_points
from swarmdeck.devices.fleet import ChargerLayout
from swarmdeck.devices.validation import colliding_pairs, out_of_bounds

ROBOT = GritsBotParams()


def test_default_layout_docks_fifty_robots_inside_the_arena_safely_apart():
    layout = ChargerLayout()
    docks = layout.dock_poses()
    assert layout.n_slots == 50 == len(docks)
    assert not out_of_bounds(docks, layout.bounds).any()
    assert len(colliding_pairs(docks)) == 0
    pts = lookahead_points(docks, ROBOT.lookahead)
    d = np.hypot(*(pts[:, None] - pts[None]).transpose(2, 0, 1)) + np.eye(50)
    assert d.min() >= 0.17
    layout.check_reachable(layout.bounds, 0.17, ROBOT.lookahead, ROBOT.radius)


def test_docked_robots_back_onto_their_wall_and_approach_poses_lie_straight_ahead():
    layout = ChargerLayout()
    docks, walls, app = layout.dock_poses(), layout.slot_walls(), layout.approach_poses()
    x0, x1, y0, y1 = layout.bounds
    gap = np.select([walls == 0, walls == 1, walls == 2], [docks[:, 1] - y0, y1 - docks[:, 1], docks[:, 0] - x0],
                    x1 - docks[:, 0])
    assert np.allclose(gap, layout.dock_depth)
    # the back (heading + π) points at the wall: moving backwards reduces the gap
    back = docks[:, :2] - 0.01 * np.column_stack((np.cos(docks[:, 2]), np.sin(docks[:, 2])))
    gap_back = np.select([walls == 0, walls == 1, walls == 2], [back[:, 1] - y0, y1 - back[:, 1], back[:, 0] - x0],
                         x1 - back[:, 0])
    assert np.all(gap_back < gap)
    dist = np.hypot(*(app[:, :2] - docks[:, :2]).T)
    # every second slot along a wall has its approach pose further in (room to turn in front of the strip)
    assert set(np.round(dist, 9)) == {layout.approach_distance, layout.approach_distance + layout.approach_stagger}
    assert np.all(np.abs(np.diff(dist[walls == 0])) > 0.1)
    assert np.allclose(app[:, 2], docks[:, 2])


def test_a_larger_arena_gets_more_slots_and_fewer_walls_fewer():
    assert ChargerLayout(bounds=(-5.0, 5.0, -3.0, 3.0)).n_slots > 150
    assert ChargerLayout(walls=("bottom", "top")).n_slots == 32


@pytest.mark.parametrize("kwargs, match", [
    (dict(slot_spacing=0.15), r"slots 0 and 1 are unreachable together.*0\.150 m apart"),
    (dict(dock_depth=0.04), "dock_depth 0.04 m is less than the robot radius"),
    (dict(corner_clearance=0.1), r"slots \d+ and \d+ are unreachable together"),
])
def test_unreachable_slots_are_named(kwargs, match):
    layout = ChargerLayout(**kwargs)
    with pytest.raises(ValueError, match=match):
        layout.check_reachable(layout.bounds, 0.17, ROBOT.lookahead, ROBOT.radius)


def test_a_layout_for_a_larger_floor_is_unreachable_in_a_smaller_arena():
    layout = ChargerLayout(bounds=(-2.0, 2.0, -1.0, 1.0))
    with pytest.raises(ValueError, match=r"charger slot 0 at \(-1\.710, -0\.940\) m is unreachable: it lies outside"):
        layout.check_reachable((-1.6, 1.6, -1.0, 1.0), 0.17, ROBOT.lookahead, ROBOT.radius)


@pytest.mark.parametrize("kwargs", [dict(walls=("north",)), dict(slot_spacing=float("nan")), dict(dock_depth=-1.0),
                                    dict(approach_distance=0.95), dict(bounds=(1, 0, 0, 1))])
def test_bad_layouts_are_refused(kwargs):
    with pytest.raises(ValueError):
        ChargerLayout(**kwargs)


def test_docked_slot_names_the_slot_a_robot_backs_onto_and_minus_one_otherwise():
    layout = ChargerLayout()
    docks = layout.dock_poses()
    poses = np.vstack((docks[[3, 40]], docks[7] + [0.05, 0.0, 0.0], docks[9] + [0.0, 0.0, np.pi],
                       [[0.0, 0.0, 0.0], [np.nan, 0.0, 0.0]]))
    poses[1, :2] += 0.01  # within the 2 cm tolerance
    assert layout.docked_slot(poses).tolist() == [3, 40, -1, -1, -1, -1]

def test_corner_slots_are_ordered_and_no_two_block_each_other():
    layout = ChargerLayout()
    blocks = layout.dock_blocks()
    assert blocks.any() and not (blocks & blocks.T).any()
    walls = layout.slot_walls()
    a, b = np.nonzero(blocks)
    assert np.all(walls[a] != walls[b])  # only at the corners
    clash = layout.approaches_clash()
    assert np.array_equal(clash, clash.T) and clash.any()
