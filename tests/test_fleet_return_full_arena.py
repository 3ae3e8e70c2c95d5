"""Return to the chargers of a full arena: 50 robots from their post-experiment poses onto all 50 slots.

Before the return retraced a planned setup, 50 on 50 never finished within its limit (the corner
slots and the crowd in front of the strips jammed); the 10-seed sweep is in bench/bench_fleet.py.
"""
import numpy as np

from swarmdeck.core.kinematics import lookahead_points
from swarmdeck.devices.fleet import ChargerLayout, FleetManager, Maneuver, return_maneuver
from swarmdeck.devices.fleet.retrace import RetraceManeuver, plan_retrace
from swarmdeck.devices.initial_conditions import random_initial_poses
from swarmdeck.devices.simulator import ArenaConfig


def test_fifty_robots_dock_on_all_fifty_slots_without_a_collision():
    fleet = FleetManager(50, config=ArenaConfig(seed=2))
    fleet.setup(random_initial_poses(50, fleet.config.bounds, rng=1002))
    report = fleet.return_to_chargers()
    assert report.ok and report.not_at_pose == []
    assert report.collision_steps == 0 and fleet.sim.report.steps_with_collision == 0
    assert report.sim_time < fleet.fleet.time_limit(50)
    slots = fleet.fleet.layout.docked_slot(fleet.poses(), position_tolerance=0.01, heading_tolerance=0.05)
    assert sorted(slots.tolist()) == list(range(50))  # every slot holds exactly one robot
    assert fleet.docked().all() and fleet.ready()


def pair_gaps(poses):
    """``(T,)`` least distance between two robots' look-ahead points at each tick of ``poses`` ``(T, K, 3)``."""
    q = lookahead_points(poses.reshape(-1, 3), 0.03).reshape(poses.shape[0], -1, 2)
    d = np.linalg.norm(q[:, :, None, :] - q[:, None, :, :], axis=-1)
    d[:, np.arange(d.shape[1]), np.arange(d.shape[1])] = np.inf
    return d.min(axis=(1, 2))


def test_the_plan_starts_on_the_slots_ends_at_the_poses_and_keeps_its_margin():
    layout = ChargerLayout()
    poses = random_initial_poses(8, layout.bounds, rng=3, wall_margin=0.4)
    slots = np.array([0, 5, 16, 20, 32, 36, 41, 45])
    plan = plan_retrace(poses, slots, layout, occupied=[], margin=0.008)
    assert np.array_equal(plan.poses[0], layout.dock_poses()[slots])
    assert np.all(np.hypot(*(plan.poses[-1, :, :2] - poses[:, :2]).T) <= 0.012 + 1e-9)
    assert plan.commands.shape == (plan.steps, 8, 2) and len(plan.poses) == plan.steps + 1
    # wider apart than the barrier that will play it back (D_s = 0.17 m), by about the margin
    assert pair_gaps(plan.poses).min() >= 0.17 + 0.008 - 1e-3


def test_return_maneuver_retraces_by_default_and_can_still_dock_directly():
    layout = ChargerLayout()
    poses = random_initial_poses(3, layout.bounds, rng=4, wall_margin=0.4)
    slots = np.array([3, 20, 44])
    assert isinstance(return_maneuver(poses, slots, layout), RetraceManeuver)
    direct = return_maneuver(poses, slots, layout, retrace=False)
    assert isinstance(direct, Maneuver) and not isinstance(direct, RetraceManeuver)
    assert np.array_equal(direct.goals, layout.dock_poses()[slots])
