"""swarmdeck.envs passes PettingZoo's parallel API test and Gymnasium's env checker, for every task and action kind."""
from __future__ import annotations

import warnings

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import parallel_api_test, parallel_seed_test

import swarmdeck.envs as envs


@pytest.mark.parametrize("task, action, cycles", [
    ("rendezvous", "velocity", 40), ("formation", "unicycle", 40), ("coverage", "velocity", 12),
])
def test_pettingzoo_parallel_api(task, action, cycles):
    env = envs.parallel_env(n_robots=4, task=task, action=action, max_steps=25,
                            density_obs=task == "coverage")
    parallel_api_test(env, num_cycles=cycles)  # includes an episode end by truncation (25 < cycles)
    env.close()


def test_pettingzoo_seed_test():
    parallel_seed_test(lambda: envs.parallel_env(n_robots=3, task="formation", max_steps=20))


@pytest.mark.parametrize("task, action", [("rendezvous", "velocity"), ("formation", "unicycle")])
def test_gymnasium_check_env(task, action):
    env = envs.CentralisedEnv(n_robots=3, task=task, action=action, max_steps=20)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*environment not having a spec.*")
        warnings.filterwarnings("ignore", message=".*symmetric and normalized space.*")
        check_env(env)
    obs, info = env.reset(seed=1)
    assert obs.shape == env.observation_space.shape and info["filter_change"].shape == (3,)


def test_spaces_and_observation_layout():
    env = envs.parallel_env(n_robots=5, task="formation", k_neighbours=2)
    obs, _ = env.reset(seed=3)
    o = obs["robot_1"]
    assert o.shape == (4 + 2 * 2 + 4 + 2,) and o.dtype == np.float32
    poses, pts = env.arena.poses(), env.arena.positions()
    assert np.allclose(o[:4], [poses[1, 0], poses[1, 1], np.cos(poses[1, 2]), np.sin(poses[1, 2])], atol=1e-6)
    d = np.linalg.norm(pts - pts[1], axis=1)
    d[1] = np.inf
    nearest = np.argsort(d)[:2]
    assert np.allclose(o[4:8], (pts[nearest] - pts[1]).reshape(-1), atol=1e-6)
    x0, x1, y0, y1 = env.config.bounds
    assert np.allclose(o[8:12], [pts[1, 0] - x0, x1 - pts[1, 0], pts[1, 1] - y0, y1 - pts[1, 1]], atol=1e-6)
    assert np.allclose(o[12:], env.slots[1] - pts[1], atol=1e-6)
    assert env.action_space("robot_0").shape == (2,)
    assert env.observation_space("robot_0") is env.observation_space("robot_0")


def test_rewards_follow_the_task():
    env = envs.parallel_env(n_robots=4, task="rendezvous")
    env.reset(seed=0)
    _, r, *_ = env.step({a: np.zeros(2, np.float32) for a in env.agents})
    pts = env.arena.positions()
    assert np.allclose([r[f"robot_{i}"] for i in range(4)], -np.linalg.norm(pts - pts.mean(0), axis=1))
    cov = envs.parallel_env(n_robots=4, task="coverage")
    cov.reset(seed=0)
    _, r, *_ = cov.step({a: np.zeros(2, np.float32) for a in cov.agents})
    m = cov.moments
    assert sum(r.values()) == pytest.approx(-m.cost.sum() / m.masses.sum())  # Σ r_i = −H / ∫φ
    assert all(v < 0 for v in r.values())


@pytest.mark.parametrize("kw, word", [({"task": "dance"}, "task"), ({"n_robots": 0}, "n_robots"),
                                      ({"action": "wheels"}, "action"), ({"task": "formation", "density_obs": True},
                                                                         "density_obs")])
def test_bad_configuration_is_a_value_error(kw, word):
    with pytest.raises(ValueError, match=word):
        envs.parallel_env(**{"n_robots": 3, **kw})
