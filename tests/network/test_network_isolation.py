"""A decentralised controller sees only its own view: reaching for another robot's pose — through the view or
the arena — is refused with an IsolationError naming the robot and what it read, counted, and that robot stands
still; the others carry on."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.devices import Arena
from swarmdeck.devices.decentralised import Decentralised
from swarmdeck.network import DiskTopology, IsolationError, NetworkConfig


def _arena() -> Arena:
    return Arena(initial_conditions=np.array([[-0.5, 0.0, 0.0], [0.0, 0.0, 0.0], [0.5, 0.0, 0.0]]))


def test_reading_another_robots_pose_is_refused_and_named():
    arena = _arena()

    def robot(i, view):
        if i == 1:
            return arena.poses()[0, :2] - view.pose[:2]  # robot 1 peeks at robot 0
        if i == 2:
            return view.poses[0, :2]  # robot 2 asks its view for everybody's poses
        if view.tick == 1:
            arena.step()  # robot 0 tries to step the arena (it would return everybody's poses)
        return np.array([0.05, 0.0])

    run = Decentralised(arena, robot, NetworkConfig(topology=DiskTopology(2.0)))
    for _ in range(3):
        run.step()
    assert run.errors["IsolationError"] == 7  # robots 1 and 2 every tick, robot 0 at tick 1
    texts = list(run.events)
    assert any("robot 0's controller read arena.step()" in t for t in texts)
    assert any("robot 1's controller read arena.poses()" in t for t in texts)
    assert any("robot 2's controller read 'poses'" in t for t in texts)
    assert run.last_commands[1:].tolist() == [[0.0, 0.0], [0.0, 0.0]] and run.last_commands[0, 0] == 0.05
    assert run.tick == 3 and arena.time == pytest.approx(3 * arena.config.dt)  # the refused step did not happen
    assert arena.poses().shape == (3, 3)  # outside the controllers the experimenter may read them


def test_strict_raises_the_isolation_error():
    arena = _arena()

    def robot(i, view):
        return arena.positions()[i]

    run = Decentralised(arena, robot, strict=True)
    with pytest.raises(IsolationError, match="robot 0's controller read arena.positions()"):
        run.step()


def test_the_view_offers_only_the_robots_own_things():
    seen = {}

    def robot(i, view):
        seen[i] = (view.i, view.pose.copy(), view.tick, view.neighbours.tolist(), view.readings)
        with pytest.raises(IsolationError, match="set 'pose'"):
            view.pose = np.zeros(3)
        with pytest.raises(ValueError):
            view.pose[0] = 1.0  # read-only
        return np.zeros(2)

    arena = _arena()
    run = Decentralised(arena, robot, NetworkConfig(topology=DiskTopology(0.6)),
                        sensors=lambda i: {"own": i})
    run.step()
    assert run.errors == {}
    assert seen[1][0] == 1 and seen[1][3] == [0, 2] and seen[0][3] == [1] and seen[2][4] == {"own": 2}
    assert np.allclose(seen[2][1], [0.5, 0.0, 0.0])
