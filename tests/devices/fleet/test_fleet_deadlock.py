"""Deadlock escape: a head-on meeting in a narrow gap or a one-lane corridor, and a ring of robots each blocked by
the next, all finish (the gap's and the corridor's walls are standing robots: fixed obstacles of the barrier)."""
import numpy as np
import pytest

from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.devices.fleet import Maneuver, ManeuverParams, SetupFailed, drive
from swarmdeck.devices.pipeline import barrier_filter
from swarmdeck.devices.simulator import ArenaConfig, SimulatedArena

ROBOT = GritsBotParams()
BOUNDS = (-1.6, 1.6, -1.0, 1.0)
NO_ESCAPE = ManeuverParams(stall_time=1e9)


def run(poses_all, goals, rows, params=ManeuverParams(), time_limit=90.0):
    sim = SimulatedArena(initial_poses=poses_all, config=ArenaConfig())
    filt = barrier_filter(ROBOT, BOUNDS, 0.033, class_k="linear", gamma=20.0)
    man = Maneuver(goals, BOUNDS, ROBOT, params)
    return drive(sim, man, rows, filt, time_limit=time_limit), sim


def gap_scene():
    """A wall of standing robots across the arena with one gap; two robots must swap through it head-on."""
    ys = np.concatenate([np.arange(0.25, 0.95, 0.17), -np.arange(0.25, 0.95, 0.17)])
    wall = np.column_stack((np.zeros_like(ys), ys, np.full_like(ys, np.pi / 2)))
    start = np.array([[-0.6, 0.0, 0.0], [0.6, 0.0, np.pi]])
    goals = np.array([[0.6, 0.0, 0.0], [-0.6, 0.0, np.pi]])
    return np.vstack((start, wall)), goals, [0, 1]


def corridor_scene(length=0.72, half_width=0.2):
    """A corridor one robot wide between two rows of standing robots; two robots meet head-on inside it and
    must swap ends (one has to back out of the whole corridor)."""
    xs = np.arange(-length / 2, length / 2 + 1e-9, 0.18)
    top = np.column_stack((xs, np.full_like(xs, half_width), np.full_like(xs, np.pi / 2)))
    bottom = np.column_stack((xs, np.full_like(xs, -half_width), np.full_like(xs, -np.pi / 2)))
    end = length / 2 + 0.3
    start = np.array([[-end, 0.0, 0.0], [end, 0.0, np.pi]])
    goals = np.array([[end, 0.0, 0.0], [-end, 0.0, np.pi]])
    return np.vstack((start, top, bottom)), goals, [0, 1]


def ring_scene(k=4, radius=0.4):
    """Robots on a ring, each going to the opposite side: they meet in the middle, each blocked by the next."""
    ang = np.arange(k) * 2 * np.pi / k
    ring = np.column_stack((radius * np.cos(ang), radius * np.sin(ang), ang + np.pi))
    return ring, np.roll(ring, k // 2, axis=0), list(range(k))


@pytest.mark.parametrize("scene", [gap_scene, corridor_scene, ring_scene])
def test_deadlocks_escape_and_finish_without_collision(scene):
    poses, goals, rows = scene()
    report, sim = run(poses, goals, rows)
    assert report.ok and report.escapes > 0 and report.escaped
    assert sim.report.steps_with_collision == 0
    assert report.max_position_error <= 0.02 and report.max_heading_error <= np.deg2rad(5)
    walls = np.setdiff1d(np.arange(len(poses)), rows)
    assert np.array_equal(sim.poses[walls], poses[walls])  # the walls never moved


def test_the_corridor_is_one_robot_wide():
    poses, _, rows = corridor_scene()
    from swarmdeck.core.kinematics import lookahead_points

    walls = lookahead_points(np.delete(poses, rows, axis=0), ROBOT.lookahead)
    # a robot on the corridor's centre line clears the walls' look-ahead points (D_s = 0.17 m) …
    assert np.min(np.abs(walls[:, 1])) >= 0.17
    # … but the band its look-ahead point may use is narrower than D_s: two robots cannot pass side by side
    assert 2 * (np.min(np.abs(walls[:, 1])) - 0.17) < 0.17


def test_without_the_escape_the_ring_stays_stuck():
    poses, goals, rows = ring_scene()
    with pytest.raises(SetupFailed, match="did not finish within 40 s"):
        run(poses, goals, rows, NO_ESCAPE, time_limit=40.0)
