"""A Gymnasium single-agent wrapper for centralised control of the whole swarm.

:class:`CentralisedEnv` drives a :class:`~swarmdeck.envs.swarm.SwarmParallelEnv`
with one controller: the observation is every robot's observation
concatenated (N·D,), the action every robot's action concatenated (N·2,)
(row i = robot i), the reward the sum of the robots' rewards; ``truncated`` after
``max_steps``. ``info`` holds per-robot arrays: ``filter_change`` (N,) and
``command_change`` (N,) in m/s, ``filter_active`` (N,) bool, and ``min_distance`` m.
Checked with ``gymnasium.utils.env_checker.check_env``.
"""
from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from swarmdeck.envs.swarm import EnvConfig, SwarmParallelEnv


class CentralisedEnv(gymnasium.Env):
    """One agent that commands every robot (see the module docstring). Keyword arguments: :class:`EnvConfig`."""

    metadata = {"render_modes": []}

    def __init__(self, config: EnvConfig | None = None, **kwargs: Any) -> None:
        self.swarm = SwarmParallelEnv(config if config is not None else EnvConfig(**kwargs))
        agents = self.swarm.possible_agents
        self.n = len(agents)
        o = self.swarm.observation_space(agents[0])
        a = self.swarm.action_space(agents[0])
        self.observation_space = spaces.Box(np.tile(o.low, self.n), np.tile(o.high, self.n), dtype=np.float32)
        self.action_space = spaces.Box(np.tile(a.low, self.n), np.tile(a.high, self.n), dtype=np.float32)
        self.render_mode = None

    def _flat(self, obs: dict[str, NDArray[np.float32]]) -> NDArray[np.float32]:
        return np.concatenate([obs[a] for a in self.swarm.possible_agents])

    def _info(self, infos: dict[str, dict[str, Any]]) -> dict[str, Any]:
        rows = [infos[a] for a in self.swarm.possible_agents]
        return {"filter_change": np.array([r["filter_change"] for r in rows]),
                "command_change": np.array([r["command_change"] for r in rows]),
                "filter_active": np.array([r["filter_active"] for r in rows]),
                "filter_status": rows[0]["filter_status"], "min_distance": rows[0]["min_distance"]}

    def reset(self, *, seed: int | None = None, options: dict | None = None
              ) -> tuple[NDArray[np.float32], dict[str, Any]]:
        super().reset(seed=seed)
        obs, infos = self.swarm.reset(seed=seed, options=options)
        return self._flat(obs), self._info(infos)

    def step(self, action: Any) -> tuple[NDArray[np.float32], float, bool, bool, dict[str, Any]]:
        a = np.asarray(action, dtype=float)
        if a.shape != self.action_space.shape:
            raise ValueError(f"the swarm's action must have shape {self.action_space.shape} "
                             f"({self.n} robots x 2), got shape {a.shape}")
        rows = a.reshape(self.n, 2)
        obs, rewards, _, truncations, infos = self.swarm.step(
            {agent: rows[i] for i, agent in enumerate(self.swarm.possible_agents)})
        return (self._flat(obs), float(sum(rewards.values())), False, bool(any(truncations.values())),
                self._info(infos))

    def close(self) -> None:
        self.swarm.close()
