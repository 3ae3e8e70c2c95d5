"""The batched environment is E separate environments at once, bit for bit: swarm e of BatchedEnv(seed=s) equals
parallel_env(barrier="distributed") reset with seed s + e (the Arena's pipeline: certify, the distributed barrier,
the simulator), in closed loop with the barrier acting; and the batched barrier equals E UnicycleSafetyFilter calls
on dense scenes with overlaps (the recovery path)."""
from __future__ import annotations

import numpy as np
import pytest

import swarmdeck.envs as envs
from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.envs import BatchedEnv, scenarios
from swarmdeck.envs.batched_barrier import BatchedDistributedBarrier
from swarmdeck.safety import BarrierConfig, UnicycleSafetyFilter


def _agents_dict(env, rows):
    return {a: rows[i] for i, a in enumerate(env.possible_agents)}


@pytest.mark.parametrize("task,safety", [("rendezvous", True), ("formation", True), ("rendezvous", False)])
def test_batched_swarms_equal_separate_environments(task, safety):
    e_count, n, steps = 4, 9, 45
    scenario = (scenarios.Rendezvous if task == "rendezvous" else scenarios.Formation)(n_agents=n, max_steps=steps)
    batched = BatchedEnv(scenario, e_count, safety=safety)
    obs, _ = batched.reset(seed=20)
    singles = [envs.parallel_env(n_robots=n, task=task, barrier="distributed", safety=safety, max_steps=steps)
               for _ in range(e_count)]
    first = [s.reset(seed=20 + e)[0] for e, s in enumerate(singles)]
    for e, s in enumerate(singles):
        assert np.array_equal(obs[e], np.stack([first[e][a] for a in s.possible_agents]))
    rng = np.random.default_rng(0)
    changed = 0
    for t in range(steps):
        pts = batched.sim.points()
        towards = 0.6 * (pts.mean(axis=1, keepdims=True) - pts)  # crowd the centre: the barrier has work
        act = (towards + rng.normal(0, 0.05, towards.shape)).astype(np.float32)
        obs, rew, term, trunc, info = batched.step(act)
        for e, s in enumerate(singles):
            o, r, te, tr, inf = s.step(_agents_dict(s, act[e]))
            agents = s.possible_agents
            assert np.array_equal(np.stack([o[a] for a in agents]), obs[e]), (t, e)
            assert np.array_equal(np.array([r[a] for a in agents]), rew[e]), (t, e)
            assert np.array_equal(np.array([inf[a]["filter_change"] for a in agents]), info["filter_change"][e])
            assert np.array_equal(np.array([inf[a]["command_change"] for a in agents]), info["command_change"][e])
            assert inf[agents[0]]["min_distance"] == info["min_distance"][e]
            assert np.array_equal(s.arena.poses(), batched.sim.poses[e]), (t, e)
            assert tr[agents[0]] == trunc[e] and not term[e]
        changed += int(np.count_nonzero(info["filter_change"]))
    assert (changed > 50) == safety  # the barrier did act (and only when on)
    assert trunc.all()


def test_batched_barrier_equals_one_filter_per_swarm_on_overlapping_scenes():
    params = GritsBotParams()
    cfg = BarrierConfig(mode="distributed")
    single = UnicycleSafetyFilter(cfg, params)
    batched = BatchedDistributedBarrier(cfg, params)
    rng = np.random.default_rng(11)
    e_count, n = 6, 40
    for _ in range(5):
        xy = rng.uniform([-1.5, -0.95], [1.5, 0.95], (e_count, n, 2))  # dense: some pairs overlap (h < 0)
        poses = np.concatenate((xy, rng.uniform(-np.pi, np.pi, (e_count, n, 1))), axis=2).reshape(-1, 3)
        v = rng.uniform(-0.2, 0.2, e_count * n)
        w = rng.uniform(-3.0, 3.0, e_count * n)
        res = batched.filter(poses, v, w, e_count)
        unsafe = 0
        for e in range(e_count):
            sl = slice(e * n, (e + 1) * n)
            vs, ws, diag = single.filter(poses[sl], v[sl], w[sl])
            assert res.ok[e] == diag.ok
            assert np.array_equal(vs, res.v[sl]) and np.array_equal(ws, res.w[sl])
            assert np.array_equal(diag.intervention, res.intervention[sl])
            unsafe += diag.n_unsafe
        assert unsafe > 0  # the recovery path was exercised
