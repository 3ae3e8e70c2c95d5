"""Virtual robots as robot ports and as an Arena backend: N = physical + virtual robots, an is_virtual mask
the only difference, commands split by id, one barrier for all, start poses clear of the physical robots."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.devices import Arena, ArenaConfig, colliding_pairs
from swarmdeck.devices.simulated_robots import SimulatedRobots
from swarmdeck.devices.virtual_robots import MixedRobots, virtual_ids, virtual_start_poses


def test_start_poses_keep_clear_of_physical_robots_and_name_the_maximum():
    physical = np.array([[0.0, 0.0], [0.5, 0.3], [-1.0, -0.6]])
    start = virtual_start_poses(20, physical, (-1.6, 1.6, -1.0, 1.0), seed=1)
    d = np.linalg.norm(start[:, None, :2] - physical[None], axis=2)
    assert d.min() >= 0.23
    assert len(colliding_pairs(np.vstack((start, np.column_stack((physical, np.zeros(3))))))) == 0
    with pytest.raises(ValueError, match="at most"):
        virtual_start_poses(500, physical, (-1.6, 1.6, -1.0, 1.0))
    assert virtual_ids(3, [4, 0, 7]).tolist() == [8, 9, 10]
    assert virtual_ids(2, []).tolist() == [0, 1]


def _mixed(n_physical: int = 3, k: int = 4, seed: int = 2) -> tuple[MixedRobots, SimulatedRobots]:
    physical = SimulatedRobots(n_physical, ArenaConfig(seed=seed))
    return MixedRobots.add_virtual(physical, physical, k, ArenaConfig(seed=seed + 1)), physical


def test_reading_marks_the_virtual_robots_and_commands_go_by_id():
    mixed, physical = _mixed()
    r = mixed.read(0.0)
    assert r.ids.tolist() == [0, 1, 2, 3, 4, 5, 6]
    assert r.is_virtual.tolist() == [False] * 3 + [True] * 4 and r.seen.all()
    before_v, before_p = mixed.virtual.sim.poses.copy(), physical.sim.poses.copy()
    v = np.where(r.ids == 5, 0.1, np.where(r.ids == 2, 0.05, 0.0))  # one virtual, one physical robot drive
    mixed.send(r.ids, v, np.zeros(7))
    moved_v = np.linalg.norm(mixed.virtual.sim.poses[:, :2] - before_v[:, :2], axis=1)
    moved_p = np.linalg.norm(physical.sim.poses[:, :2] - before_p[:, :2], axis=1)
    assert np.flatnonzero(moved_v).tolist() == [2]  # virtual ids 3..6: id 5 is the simulation's row 2
    assert np.flatnonzero(moved_p).tolist() == [2]
    assert "virtual: 4 robots" in mixed.health()
    with pytest.raises(ValueError, match="distinct ids"):
        MixedRobots(physical, physical, mixed.virtual, [7, 7, 8, 9])


def test_a_physical_id_clashing_with_a_virtual_one_is_named():
    physical = SimulatedRobots(3, ArenaConfig(seed=1))
    virtual = SimulatedRobots(2, ArenaConfig(seed=2))
    mixed = MixedRobots(physical, physical, virtual, [2, 3])
    with pytest.raises(ValueError, match=r"physical robot id\(s\) \[2\]"):
        mixed.read(0.0)


def test_console_loop_certifies_physical_and_virtual_robots_together():
    mixed, _ = _mixed(4, 4, seed=6)
    loop = ControlLoop(LoopConfig(n_robots=4, behaviour="rendezvous"), source=mixed, sink=mixed)
    frames = [loop.tick() for _ in range(400)]
    loop.close()
    assert all(f.is_virtual.tolist() == [False] * 4 + [True] * 4 for f in frames)
    assert all(len(colliding_pairs(f.poses)) == 0 and f.barrier.ok for f in frames)
    crossing = [p for f in frames for p in f.barrier.active_pairs if f.is_virtual[p[0]] != f.is_virtual[p[1]]]
    assert crossing  # a physical robot yielded to a virtual one (and the other way round)


def test_arena_sees_n_robots_and_an_is_virtual_mask():
    physical = SimulatedRobots(3, ArenaConfig(seed=3))
    arena = Arena(backend=MixedRobots.add_virtual(physical, physical, 4, ArenaConfig(seed=4)))
    assert arena.n == 7 and arena.is_virtual.tolist() == [False] * 3 + [True] * 4
    mask = arena.is_virtual
    mask[:] = True  # a copy: user code cannot change which robots are virtual
    assert arena.is_virtual.sum() == 4
    for _ in range(300):
        p = arena.positions()
        arena.set_velocities(p.mean(axis=0) - p)
        arena.step()
        assert len(colliding_pairs(arena.poses())) == 0
    assert arena.safety_stats.failures == 0 and arena.safety_stats.interventions > 0
    assert np.array_equal(arena.poses()[:3], physical.sim.poses)  # rows 0..2 are the physical robots
    assert Arena(3).is_virtual.tolist() == [False] * 3
    with pytest.raises(ValueError, match=r"\(7,\)"):
        arena.robots.step(np.zeros(6), np.zeros(6))
