"""Decentralised isolation: each robot's controller runs in its own process, so a hostile script that passes robot 0's
pose to robot 1 through a module global finds nothing there — in the sandbox (where it is always so, and where the
network lives on the trusted side) and in process with ``Decentralised(isolate=True)``. The failing controller is
named, counted, its robot stopped, with the reason (globals are not shared between robots)."""
from __future__ import annotations

import re
import textwrap

import numpy as np
import pytest

from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.decentralised import Decentralised
from swarmdeck.devices.simulator import ArenaConfig
from swarmdeck.network import KNearestTopology, NetworkConfig

START = [[-0.6, 0.0, 0.0], [0.0, 0.0, 0.0], [0.6, 0.0, 0.0]]

# robot 1 follows robot 0 through a global, past the network; the others broadcast their position
SHARING = """
    import numpy as np
    from swarmdeck.devices import Arena
    from swarmdeck.devices.decentralised import Decentralised
    from swarmdeck.network import KNearestTopology, NetworkConfig

    SEEN = {}  # every robot's controller writes its position here: a back channel between robots

    def robot(i, view):
        SEEN[i] = view.position.copy()
        if i == 1:
            return SEEN[0] - view.position  # robot 1 reads robot 0's position
        view.broadcast(view.position)
        return np.zeros(2)

    arena = Arena()
    run = Decentralised(arena, robot, NetworkConfig(topology=KNearestTopology(2), seed=1))
    try:
        while True:
            run.step()
    finally:
        print("key errors:", run.errors["KeyError"], "ticks:", run.tick, "delivered:", run.network.stats["delivered"])
        print(run.events[0])
"""


def _sharing_robot(shared):
    def robot(i, view):
        shared[i] = view.position.copy()
        if i == 1:
            return shared[0] - view.position
        view.broadcast(view.position)
        return np.zeros(2)

    return robot


def test_a_global_shared_between_controllers_reaches_no_other_robot_in_process():
    arena = Arena(initial_conditions=START, config=ArenaConfig(seed=1))
    run = Decentralised(arena, _sharing_robot({}), NetworkConfig(topology=KNearestTopology(2), seed=1), isolate=True)
    try:
        for _ in range(5):
            run.step()
    finally:
        run.close()
    assert run.errors["KeyError"] == 5  # robot 1 found only its own entry, every tick
    assert "robot 1's controller raised KeyError" in run.events[0]
    assert "not shared between robots" in run.events[0]
    assert np.allclose(arena.poses()[1], START[1])  # stopped
    assert run.network.stats["delivered"] > 0  # the others talked over the network meanwhile


def test_without_isolation_the_same_global_is_a_back_channel():
    arena = Arena(initial_conditions=START, config=ArenaConfig(seed=1))
    run = Decentralised(arena, _sharing_robot({}), NetworkConfig(topology=KNearestTopology(2), seed=1))
    run.step()
    assert not run.errors and run.last_commands[1, 0] < 0  # robot 1 heads for robot 0: why the sandbox isolates


def test_a_controller_process_cannot_reach_the_arena():
    arena = Arena(initial_conditions=START, config=ArenaConfig(seed=1))

    def peek(i, view):
        return arena.poses()[0, :2] - view.position

    run = Decentralised(arena, peek, isolate=True)
    try:
        run.step()
    finally:
        run.close()
    assert run.errors["IsolationError"] == 3
    assert arena.poses().shape == (3, 3)  # the script's own process is not sealed after the tick


@pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
def test_a_sandboxed_script_sharing_a_global_between_robots_is_stopped_and_told_why(tmp_path):
    script = tmp_path / "sharing.py"
    script.write_text(textwrap.dedent(SHARING))
    plants = []

    def make_plant(n, initial):
        plants.append(ArenaPlant(Arena(initial_conditions=START, config=ArenaConfig(seed=2), duration=0.5)))
        return plants[-1]

    out = run_sandboxed(script, make_plant, n_robots=3, duration=0.5)
    assert out.ok, out.error
    plant = plants[0]
    errors, ticks = re.search(r"key errors: (\d+) ticks: (\d+)", out.log).groups()
    assert errors == ticks != "0", out.log  # robot 1 failed every tick
    assert "robot 1's controller raised KeyError: 0" in out.log and "not shared between robots" in out.log
    assert np.allclose(plant.arena.poses()[1], START[1])  # robot 1 stood still
    trusted = plant.trusted_network.network  # the network lived on the trusted side and delivered the broadcasts
    assert trusted.stats["delivered"] > 0
    told = int(re.search(r"delivered: (\d+)", out.log).group(1))  # the script's counts are the trusted side's
    assert 0 < told <= trusted.stats["delivered"]  # (up to its last tick: the trusted side stepped once more)
