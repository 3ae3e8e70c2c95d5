"""The return as the setup played backwards: the plan, its playback, and the docking logic when playback stalls."""
import numpy as np

from swarmdeck.core.kinematics import GritsBotParams, lookahead_points
from swarmdeck.devices.fleet import ChargerLayout, Maneuver, drive, return_maneuver
from swarmdeck.devices.fleet.retrace import RetraceGains, RetraceManeuver, plan_retrace
from swarmdeck.devices.initial_conditions import random_initial_poses
from swarmdeck.devices.pipeline import barrier_filter
from swarmdeck.devices.simulator import ArenaConfig, SimulatedArena

LAYOUT = ChargerLayout()
ROBOT = GritsBotParams()


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


def play(man, start, time_limit=120.0):
    sim = SimulatedArena(initial_poses=start, config=ArenaConfig())
    filt = barrier_filter(ROBOT, LAYOUT.bounds, 0.033, class_k="linear", gamma=20.0)
    return drive(sim, man, np.arange(len(start)), filt, time_limit=time_limit, what="return"), sim


def test_played_back_from_where_the_plan_ends_every_robot_docks_before_the_plan_runs_out():
    poses = random_initial_poses(6, LAYOUT.bounds, rng=7, wall_margin=0.4)
    slots = np.array([2, 9, 18, 27, 34, 43])
    man = return_maneuver(poses, slots, LAYOUT)
    report, sim = play(man, poses)
    assert report.ok and sim.report.steps_with_collision == 0
    assert np.all(np.hypot(*(sim.poses[:, :2] - LAYOUT.dock_poses()[slots, :2]).T) <= 0.01)
    assert report.escapes == 0  # tracked, not escaped


def test_robots_pushed_off_the_plan_stall_its_clock_and_the_docking_logic_takes_over():
    poses = random_initial_poses(3, LAYOUT.bounds, rng=8, wall_margin=0.5)
    slots = np.array([6, 22, 38])
    man = RetraceManeuver(plan_retrace(poses, slots, LAYOUT), slots, LAYOUT, gains=RetraceGains(give_up=2.0))
    pushed = poses + [0.06, 0.0, 0.0]  # 6 cm from where the plan starts: beyond lag_stop, most clocks never run
    report, sim = play(man, pushed)
    assert not man.replaying and man._s.max() < man.plan.steps  # handed over before the plan ran out
    assert report.ok and sim.report.steps_with_collision == 0
    assert report.sim_time > 2.0
