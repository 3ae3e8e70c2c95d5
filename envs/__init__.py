"""swarmdeck.envs: learning environments on the simulated arena (``pip install 'swarmdeck[rl]'``).

    import swarmdeck.envs
    env = swarmdeck.envs.parallel_env(n_robots=10, task="coverage")   # PettingZoo ParallelEnv
    obs, infos = env.reset(seed=0)
    while env.agents:
        actions = {a: env.action_space(a).sample() for a in env.agents}
        obs, rewards, terminations, truncations, infos = env.step(actions)
        # infos[a]["filter_change"]: how much the safety filter changed robot a's command, m/s

    single = swarmdeck.envs.CentralisedEnv(n_robots=10, task="rendezvous")  # Gymnasium Env

    batched = swarmdeck.envs.BatchedEnv(swarmdeck.envs.scenarios.Rendezvous(n_agents=10), n_envs=64)
    obs, info = batched.reset(seed=0)          # (64, 10, D): 64 swarms stepped at once (swarmdeck.envs.batched)

Every action passes the barrier-certificate safety filter of ``swarmdeck.safety``
(through ``swarmdeck.devices.Arena``) unless ``safety=False``. Episodes can be
recorded to MCAP and played in the console: ``swarmdeck.console.recording.episodes``.
"""
from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from swarmdeck.envs import scenarios
from swarmdeck.envs.scenario import Actions, Scenario, View
from swarmdeck.envs.tasks import TASKS

if TYPE_CHECKING:
    from swarmdeck.envs.batched import BatchedEnv, ScenarioParallelEnv, SwarmVectorEnv
    from swarmdeck.envs.centralised import CentralisedEnv
    from swarmdeck.envs.swarm import ACTIONS, EnvConfig, SwarmParallelEnv, parallel_env

# The environments need the 'rl' extra (gymnasium, pettingzoo); the scenarios and a trained policy
# (swarmdeck.envs.policy, swarmdeck.envs.deploy: what a sandboxed experiment script imports) need only numpy.
_NEEDS_RL = {"BatchedEnv": "batched", "ScenarioParallelEnv": "batched", "SwarmVectorEnv": "batched",
             "CentralisedEnv": "centralised", "ACTIONS": "swarm", "EnvConfig": "swarm", "SwarmParallelEnv": "swarm",
             "parallel_env": "swarm"}


def __getattr__(name: str) -> Any:
    if name in _NEEDS_RL:
        return getattr(importlib.import_module(f"swarmdeck.envs.{_NEEDS_RL[name]}"), name)
    raise AttributeError(f"module 'swarmdeck.envs' has no attribute {name!r}")

__all__ = ["ACTIONS", "Actions", "BatchedEnv", "CentralisedEnv", "EnvConfig", "Scenario", "ScenarioParallelEnv",
           "SwarmParallelEnv", "SwarmVectorEnv", "TASKS", "View", "parallel_env", "scenarios"]
