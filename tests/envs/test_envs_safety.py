"""Every env action passes the safety filter, the info dict reports by how much, and bad actions are ValueErrors."""
from __future__ import annotations

import numpy as np
import pytest

import swarmdeck.envs as envs

D_S = 0.17


def _rush_together(safety: bool, steps: int = 90):
    """Six robots driven straight at their common centre; returns the infos of every step."""
    env = envs.parallel_env(n_robots=6, task="rendezvous", safety=safety, max_steps=steps)
    env.reset(seed=4)
    out = []
    while env.agents:
        p = env.arena.positions()
        u = 0.2 * (p.mean(axis=0) - p) / np.maximum(np.linalg.norm(p.mean(axis=0) - p, axis=1, keepdims=True), 1e-9)
        _, _, _, _, infos = env.step({a: u[i].astype(np.float32) for i, a in enumerate(env.possible_agents)})
        out.append(infos)
    return out


def test_filter_changes_unsafe_actions_and_says_so():
    on = _rush_together(True)
    change = np.array([[i[a]["filter_change"] for a in sorted(i)] for i in on])
    assert change.max() > 0.01 and any(i["robot_0"]["filter_status"] for i in on)
    active = np.array([[i[a]["filter_active"] for a in sorted(i)] for i in on])
    assert np.array_equal(active, change > 1e-9)
    assert min(i["robot_0"]["min_distance"] for i in on) >= D_S - 0.01  # the barrier held them apart
    off = _rush_together(False)
    assert all(i[a]["filter_change"] == 0.0 and not i[a]["filter_active"] for i in off for a in i)
    assert min(i["robot_0"]["min_distance"] for i in off) < D_S - 0.03  # without it they crowd in


@pytest.mark.parametrize("bad, words", [
    (np.array([np.nan, 0.0]), ["robot_2", "(2,)", "NaN"]),
    (np.array([0.1, 0.0, 0.0]), ["robot_2", "shape (2,)", "(3,)"]),
    ("fast", ["robot_2", "shape (2,)"]),
])
def test_bad_actions_are_value_errors_naming_agent_and_shape(bad, words):
    env = envs.parallel_env(n_robots=3, task="formation")
    env.reset(seed=0)
    before = env.arena.poses()
    acts = {a: np.zeros(2, np.float32) for a in env.agents}
    acts["robot_2"] = bad
    with pytest.raises(ValueError) as err:
        env.step(acts)
    for w in words:
        assert w in str(err.value)
    assert env.steps == 0 and np.array_equal(env.arena.poses(), before), "a refused action does not advance the run"
    with pytest.raises(ValueError, match="unknown agent 'robot_9'"):
        env.step({"robot_9": np.zeros(2)})


def test_centralised_env_names_the_swarm_shape_and_the_robot():
    env = envs.CentralisedEnv(n_robots=3, task="rendezvous")
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"shape \(6,\).*got shape \(5,\)"):
        env.step(np.zeros(5))
    a = np.zeros(6)
    a[3] = np.inf
    with pytest.raises(ValueError, match="robot_1"):
        env.step(a)


def test_out_of_range_actions_are_clipped_to_the_space_and_the_wheels():
    env = envs.parallel_env(n_robots=2, task="rendezvous", action="unicycle", safety=False)
    env.reset(seed=0)
    _, _, _, _, infos = env.step({"robot_0": np.array([5.0, 0.0]), "robot_1": np.array([0.0, 0.0])})
    v = np.linalg.norm(env.arena.last_safe[0])
    assert v == pytest.approx(0.2, rel=1e-6)  # 5 m/s requested: the robot's top speed was sent
    assert infos["robot_1"]["command_change"] == 0.0
