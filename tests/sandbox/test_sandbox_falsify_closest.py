"""The falsifier's objective: the closest approach of a raw run (``VerificationRobots.closest``), between two robots
(centre distance − diameter) or a robot and an obstacle segment (distance − radius), with who and when."""
import numpy as np
import pytest

from swarmdeck.console.sandbox.plant import Disturbances, VerificationRobots
from swarmdeck.core.constants import ROBOT_DIAMETER, ROBOT_RADIUS
from swarmdeck.core.obstacles import Obstacles
from swarmdeck.devices.simulator import ArenaConfig, SimulatedArena

QUIET = Disturbances(pose_noise_xy=0.0, pose_noise_theta=0.0, latency_ticks=0, drop_probability=0.0)


def drive(poses, steps, v, obstacles=None):
    config = ArenaConfig(seed=None, obstacles=obstacles)
    sim = SimulatedArena(len(poses), np.array(poses, dtype=float), config=config)
    robots = VerificationRobots(sim, QUIET, np.random.default_rng(0), contact_distance=sim.params.diameter)
    for _ in range(steps):
        robots.step(np.asarray(v, dtype=float), np.zeros(len(poses)))
    return robots


def test_two_robots_closest_approach_names_the_pair_and_the_time():
    # robots 1 and 2 drive towards each other at 0.1 m/s: after 15 steps their centres are 0.3 − 2 · 0.1 · 15 dt apart
    robots = drive([[-1.0, 0.5, 0.0], [-0.15, 0.0, 0.0], [0.15, 0.0, np.pi]], 15, [0.0, 0.1, 0.1])
    c = robots.closest
    assert c.kind == "robots" and (c.first, c.second) == (1, 2)
    assert c.clearance == pytest.approx(0.3 - 2 * 0.1 * 15 * robots.sim.config.dt - ROBOT_DIAMETER, abs=1e-6)
    assert c.time == pytest.approx(15 * robots.sim.config.dt)


def test_a_robot_near_an_obstacle_segment_is_the_closest_approach():
    wall = Obstacles.of([[[0.5, -0.5], [0.5, 0.5]]])
    robots = drive([[0.2, 0.0, 0.0], [-1.0, 0.6, 0.0]], 10, [0.1, 0.0], obstacles=wall)
    c = robots.closest
    x = 0.2 + 0.1 * 10 * robots.sim.config.dt
    assert c.kind == "obstacle" and (c.first, c.second) == (0, 0)
    assert c.clearance == pytest.approx(0.5 - x - ROBOT_RADIUS, abs=1e-6)


def test_nothing_near_leaves_the_closest_approach_infinite():
    robots = drive([[0.0, 0.0, 0.0]], 3, [0.0])
    assert robots.closest.clearance == float("inf") and robots.closest.kind == ""
