"""The learning environment's optional ToF block (issue 28.1): ``EnvConfig(sensors=DistanceSensorConfig())`` adds
each robot's own seven readings / range (1: nothing in range) to its observation, within the declared space,
deterministic under ``reset(seed)``; without it the observations are unchanged."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.envs.swarm import EnvConfig, SwarmParallelEnv
from swarmdeck.sensing import DistanceSensorConfig


def _run(seed: int, steps: int = 5) -> list[dict]:
    env = SwarmParallelEnv(EnvConfig(n_robots=8, sensors=DistanceSensorConfig()))
    obs, _ = env.reset(seed=seed)
    out = [obs]
    for _ in range(steps):
        obs, *_ = env.step({a: np.array([0.05, 0.0], dtype=np.float32) for a in env.agents})
        out.append(obs)
    return out


def test_the_block_is_seven_readings_in_the_observation_space():
    plain = SwarmParallelEnv(EnvConfig(n_robots=8))
    env = SwarmParallelEnv(EnvConfig(n_robots=8, sensors=DistanceSensorConfig()))
    assert env.observation_space("robot_0").shape[0] == plain.observation_space("robot_0").shape[0] + 7
    for obs in _run(4):
        for a, o in obs.items():
            assert env.observation_space(a).contains(o)
            block = o[-7:]
            assert ((block >= 0) & (block <= 1)).all()
    first = _run(4, steps=0)[0]
    assert all((o[-7:] == 1.0).all() for o in first.values())  # nothing read before the first step


def test_the_same_seed_gives_the_same_readings():
    a, b = _run(9), _run(9)
    for oa, ob in zip(a, b):
        for agent in oa:
            assert np.array_equal(oa[agent], ob[agent])


def test_a_bad_sensors_value_is_named():
    with pytest.raises(ValueError, match="sensors must be a DistanceSensorConfig"):
        EnvConfig(sensors=1.2)  # type: ignore[arg-type]
