"""An experiment's robots inside the fleet (devices.fleet.assigned): the assigned fleet robots are the
experiment's robots 0..N-1 in assignment order, commands reach only them, and every other robot is a fixed
obstacle of the experiment's barrier — a script driving straight at a docked robot is stopped short of it."""
import numpy as np
import pytest

from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig, SafetyParams
from swarmdeck.core.kinematics import GritsBotParams, lookahead_points
from swarmdeck.devices import ArenaConfig
from swarmdeck.devices.chargers import ChargerLayout
from swarmdeck.devices.fleet.assigned import AssignedRobots
from swarmdeck.devices.simulated_robots import SimulatedRobots

ELL = GritsBotParams().lookahead


def docked_fleet(m=4):
    return SimulatedRobots(m, ArenaConfig(), chargers=ChargerLayout(), start_docked=True)


def test_the_assigned_robots_are_0_to_n_minus_1_and_only_they_move():
    fleet = docked_fleet()
    before = fleet.read().poses
    robots = AssignedRobots(fleet, fleet, [3, 1], ELL)
    r = robots.read()
    assert r.ids.tolist() == [0, 1] and np.allclose(r.poses, before[[3, 1]]) and r.seen.all()
    assert r.battery.shape == (2,) and r.charging.all()  # docked: charging
    assert np.allclose(robots.obstacles(), lookahead_points(before[[0, 2]], ELL))
    for _ in range(10):
        robots.read()
        robots.send(np.array([0, 1]), np.array([0.1, 0.0]), np.array([0.0, 0.5]))
    after = fleet.read().poses
    assert np.allclose(after[[0, 2]], before[[0, 2]])  # the others stood still
    assert after[3, 1] > before[3, 1] + 0.02 and abs(after[1, 2] - before[1, 2]) > 0.1
    with pytest.raises(ValueError, match="0..1"):
        robots.send(np.array([3, 1]), np.zeros(2), np.zeros(2))
    with pytest.raises(ValueError, match="distinct"):
        AssignedRobots(fleet, fleet, [2, 2], ELL)
    robots.close()
    assert np.allclose(fleet.read().poses, after)  # closing: zero once, the fleet stays


def test_a_docked_robot_is_an_obstacle_of_the_experiments_barrier():
    fleet = docked_fleet()
    start = fleet.read().poses
    robots = AssignedRobots(fleet, fleet, [3], ELL)
    # robot 3 leaves its strip, then is told to drive onto docked robot 2's position
    cfg = LoopConfig(n_robots=1, behaviour="goto", safety=SafetyParams(enabled=True))
    loop = ControlLoop(cfg, source=robots, sink=robots)
    loop.set_params(goals=((float(start[3, 0]), float(start[3, 1]) + 0.35),))
    for _ in range(150):
        loop.tick()
    loop.set_params(goals=((float(start[2, 0]), float(start[2, 1]) + 0.05),))
    closest = np.inf
    for _ in range(300):
        frame = loop.tick()
        poses = fleet.read().poses
        gap = np.hypot(*(lookahead_points(poses[[3]], ELL) - lookahead_points(poses[[2]], ELL))[0])
        closest = min(closest, gap)
    assert frame.barrier.ok
    assert closest >= cfg.safety.safety_distance - 5e-3, closest  # held off by D_s
    assert np.allclose(fleet.read().poses[[0, 1, 2]], start[[0, 1, 2]])  # nobody pushed the docked robots
    loop.close()
