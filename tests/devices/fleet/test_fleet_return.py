"""Return to the chargers: every robot docks on a free slot, safely; the arena is then ready; docked robots charge."""
import numpy as np

from swarmdeck.devices.fleet import FleetManager, choose_slots
from swarmdeck.devices.initial_conditions import random_initial_poses
from swarmdeck.devices.simulator import ArenaConfig


def test_after_an_experiment_every_robot_docks_and_the_arena_is_ready():
    fleet = FleetManager(20, config=ArenaConfig(seed=4))
    fleet.setup(random_initial_poses(12, fleet.config.bounds, rng=5, wall_margin=0.4))
    exp = fleet.experiment()
    assert fleet.ready()  # every robot docked or assigned
    for _ in range(90):  # the experiment drives the robots around a little
        exp.send(np.arange(12), np.zeros(12), np.full(12, 0.8))  # turning on the spot: drains, moves nobody
    charge_after_run = fleet.charge.copy()
    report = fleet.return_to_chargers()
    assert report.ok and report.collision_steps == 0 and fleet.sim.report.steps_with_collision == 0
    slots = fleet.fleet.layout.docked_slot(fleet.poses(), heading_tolerance=0.1)
    assert np.all(slots >= 0) and len(np.unique(slots)) == 20
    assert fleet.docked().all() and fleet.ready() and fleet.assignment is None
    assert exp.time < fleet.time  # the experiment's clock stopped when the return began
    fleet.wait(600.0)
    assert np.all(fleet.charge > charge_after_run - 0.01) and np.all(fleet.charge <= 1.0)


def test_free_slots_a_docked_robot_blocks_are_never_chosen():
    fleet = FleetManager(config=ArenaConfig(seed=0))
    layout = fleet.fleet.layout
    blocks = layout.dock_blocks()
    a, b = np.argwhere(blocks)[0]  # a docked robot on a blocks the way onto b
    free = np.array([b, (b + 5) % layout.n_slots])
    if a in free:
        free = free[free != a]
    slots = choose_slots(layout.approach_poses()[[b], :2], free, layout)
    assert slots.tolist() != [b]
