"""Return to the chargers of a full arena: 50 robots from their post-experiment poses onto all 50 slots.

Before the return retraced a planned setup, 50 on 50 never finished within its limit (the corner
slots and the crowd in front of the strips jammed); the 10-seed sweep is in bench/bench_fleet.py.
"""

from swarmdeck.devices.fleet import FleetManager
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
