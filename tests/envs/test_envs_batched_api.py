"""The batched environment's conventions: PettingZoo's parallel API test on shipped scenarios, Gymnasium's vector-env
contract (batched spaces, next-step autoreset, seeding), and clear errors for bad actions."""
from __future__ import annotations

import numpy as np
import pytest
from gymnasium.vector import AutoresetMode
from pettingzoo.test import parallel_api_test

from swarmdeck.envs import BatchedEnv, ScenarioParallelEnv, SwarmVectorEnv, scenarios


@pytest.mark.parametrize("scenario", [scenarios.PredatorCapturePrey(max_steps=4), scenarios.Warehouse(max_steps=3),
                                      scenarios.Rendezvous(n_agents=5, max_steps=25),
                                      scenarios.Formation(n_agents=4, max_steps=25)])
def test_pettingzoo_parallel_api(scenario):
    parallel_api_test(ScenarioParallelEnv(scenario), num_cycles=40)


def test_agents_are_named_by_kind():
    env = ScenarioParallelEnv(scenarios.PredatorCapturePrey())
    assert env.possible_agents == ["predator_0", "predator_1", "capture_2", "capture_3"]


def test_gymnasium_vector_env_contract():
    env = SwarmVectorEnv(scenarios.Warehouse(max_steps=2), 3)
    assert env.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP and env.num_envs == 18
    obs, info = env.reset(seed=4)
    assert obs.shape == (18, 18) and obs.dtype == np.float32 and env.observation_space.contains(obs)
    again, _ = SwarmVectorEnv(scenarios.Warehouse(max_steps=2), 3).reset(seed=4)
    assert np.array_equal(obs, again)
    seen_truncation = False
    for _ in range(6):
        was_done = seen_truncation
        obs, rew, term, trunc, info = env.step(env.action_space.sample())
        assert env.observation_space.contains(obs) and rew.shape == term.shape == trunc.shape == (18,)
        assert rew.dtype == np.float64 and term.dtype == trunc.dtype == np.bool_
        if was_done:  # the step after the end: every swarm starts over, zero reward
            assert not trunc.any() and not rew.any()
        seen_truncation = bool(trunc.all())
    vel = SwarmVectorEnv(scenarios.Rendezvous(n_agents=3), 2)
    vel.reset(seed=0)
    obs, *_ = vel.step(vel.action_space.sample())
    assert obs.shape == (6, 14) and vel.single_action_space.shape == (2,)


def test_bad_actions_are_clear_errors():
    env = BatchedEnv(scenarios.Rendezvous(n_agents=3), 2)
    with pytest.raises(RuntimeError, match="reset"):
        env.step(np.zeros((2, 3, 2)))
    env.reset(seed=0)
    with pytest.raises(ValueError, match=r"shape \(2, 3, 2\)"):
        env.step(np.zeros((2, 3)))
    bad = np.zeros((2, 3, 2))
    bad[1, 2, 0] = np.nan
    with pytest.raises(ValueError, match=r"NaN or inf at \(swarm, agent\) \[\[1, 2\]\]"):
        env.step(bad)
    moves = BatchedEnv(scenarios.Warehouse(), 1)
    moves.reset(seed=0)
    with pytest.raises(ValueError, match="ints 0..4"):
        moves.step(np.full((1, 6), 5))
    with pytest.raises(ValueError, match="n_agents"):
        scenarios.Warehouse(n_agents=0)
