"""The assigned robots' obstacles (devices.fleet.assigned) include the fleet sink's own obstacles when the sink
reports them (core.ports.ReportsObstacles), and a sink reporting none (None, as the protocol allows) adds none
instead of failing the barrier's tick."""
import numpy as np

from swarmdeck.core.kinematics import GritsBotParams, lookahead_points
from swarmdeck.devices import ArenaConfig
from swarmdeck.devices.chargers import ChargerLayout
from swarmdeck.devices.fleet.assigned import AssignedRobots
from swarmdeck.devices.simulated_robots import SimulatedRobots

ELL = GritsBotParams().lookahead


class FleetWithObstacles(SimulatedRobots):
    """A simulated fleet whose sink also knows fixed obstacles (``found``: what ``obstacles()`` returns)."""

    def __init__(self, found):
        super().__init__(4, ArenaConfig(), chargers=ChargerLayout(), start_docked=True)
        self.found = found

    def obstacles(self):
        return self.found


def test_the_sinks_obstacles_are_added_to_the_other_fleet_robots():
    fleet = FleetWithObstacles(np.array([[0.5, 0.25]]))
    poses = fleet.read().poses
    robots = AssignedRobots(fleet, fleet, [3, 1], ELL)
    want = np.vstack((lookahead_points(poses[[0, 2]], ELL), [[0.5, 0.25]]))
    assert np.allclose(robots.obstacles(), want)


def test_a_sink_that_reports_no_obstacles_adds_none():
    fleet = FleetWithObstacles(None)
    poses = fleet.read().poses
    robots = AssignedRobots(fleet, fleet, [3, 1], ELL)
    assert np.allclose(robots.obstacles(), lookahead_points(poses[[0, 2]], ELL))
