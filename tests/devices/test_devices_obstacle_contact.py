"""Line-segment obstacles in the simulator, validation and the Arena: a robot cannot pass through a segment,
contacts are counted, bad obstacle sets and start poses are refused naming the segment, and the barrier keeps
an Arena's robots off the segments."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.core.obstacles import ObstacleError, Obstacles, point_segment_distance
from swarmdeck.devices import Arena, ArenaConfig
from swarmdeck.devices.simulator import SimulatedArena

WALL = [[[-0.5, 0.0], [0.5, 0.0]]]


def test_a_robot_cannot_drive_through_a_segment() -> None:
    sim = SimulatedArena(initial_poses=np.array([[0.0, 0.3, -np.pi / 2], [1.0, 0.3, -np.pi / 2]]),
                         config=ArenaConfig(obstacles=WALL))
    for _ in range(200):
        sim.step([0.2, 0.2], [0.0, 0.0])
    p = sim.poses
    assert p[0, 1] > 0.0  # stopped in front of the wall, not through it
    assert p[1, 1] < -0.5  # the robot beside the wall drove on
    assert point_segment_distance(p[:1, :2], WALL)[0, 0] >= 0.055 - 0.2 * 0.033
    assert sim.report.steps_with_obstacle_contact > 0
    assert sim.report.obstacle_contacts_per_robot.tolist()[1] == 0
    assert "obstacle contacts" in sim.report.summary()
    assert sim.report.to_dict()["steps_with_obstacle_contact"] == sim.report.steps_with_obstacle_contact


def test_a_fast_step_cannot_tunnel_and_a_touching_robot_backs_away() -> None:
    cfg = ArenaConfig(obstacles=WALL, dt=0.5)  # 0.1 m per step: the body would jump the wall
    sim = SimulatedArena(initial_poses=np.array([[0.0, 0.07, -np.pi / 2]]), config=cfg)
    for _ in range(5):
        sim.step([0.2], [0.0])
        assert sim.poses[0, 1] > 0.0
    sim.step([-0.2], [0.0])
    assert sim.poses[0, 1] > 0.1


def test_validation_rejects_a_run_touching_obstacles_too_long() -> None:
    sim = SimulatedArena(initial_poses=np.array([[0.0, 0.3, -np.pi / 2]]), config=ArenaConfig(obstacles=WALL))
    for _ in range(300):
        sim.step([0.2], [0.0])
    assert any("touching obstacles" in r for r in sim.report.verdict())


def test_no_obstacles_report_reads_as_before() -> None:
    sim = SimulatedArena(3, config=ArenaConfig(seed=1))
    sim.step(np.zeros(3), np.zeros(3))
    assert "steps_with_obstacle_contact" not in sim.report.to_dict()
    assert "obstacle" not in sim.report.summary()


@pytest.mark.parametrize("obstacles, words", [
    ([[[0.0, 0.0], [0.0, 0.0]]], "segment 0 has zero length"),
    ([[[0.0, 0.0], [1.0, 0.0]], [[np.nan, 0.0], [1.0, 0.0]]], "segment 1 has NaN"),
    ([[[0.0, 0.0], [1.0, 0.0]], [[1.0, 0.5], [2.0, 0.5]]], "segment 1 .*outside the arena"),
])
def test_arena_refuses_bad_obstacles_naming_the_segment(obstacles: object, words: str) -> None:
    with pytest.raises(ObstacleError, match=words):
        Arena(2, obstacles=obstacles)


def test_arena_refuses_a_start_pose_behind_a_segment() -> None:
    with pytest.raises(ObstacleError, match=r"segment 0 .*crosses start pose 1"):
        Arena(initial_conditions=np.array([[1.0, 0.5, 0.0], [0.0, 0.05, 0.0]]), obstacles=WALL)


def test_random_start_poses_keep_clear_of_obstacles() -> None:
    obs = Obstacles.from_polygons([[[-1.0, -0.6], [1.0, -0.6], [1.0, 0.6], [-1.0, 0.6]]])
    arena = Arena(20, obstacles=obs, config=ArenaConfig(seed=4))
    assert point_segment_distance(arena.poses()[:, :2], obs.segments).min() >= 0.115


def test_arena_barrier_keeps_robots_off_the_segments() -> None:
    poses = np.array([[-0.3, 0.5, -np.pi / 2], [0.0, 0.5, -np.pi / 2], [0.3, 0.5, -np.pi / 2]])
    arena = Arena(initial_conditions=poses, obstacles=WALL, config=ArenaConfig(seed=0))
    goals = poses.copy()
    goals[:, 1] = -0.5
    for _ in range(250):
        arena.set_goals(goals)
        arena.step()
    report = arena.report()
    assert report.validation.steps_with_obstacle_contact == 0
    assert report.validation.steps_with_collision == 0
    assert np.all(arena.poses()[:, 1] > 0.0)
