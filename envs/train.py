"""Train a small policy on a shipped scenario with Stable-Baselines3's PPO (``pip install 'swarmdeck[learn]'``).

:func:`train` steps ``n_envs`` swarms of a :data:`swarmdeck.envs.scenarios.SHIPPED` scenario at once in a
:class:`~swarmdeck.envs.batched.BatchedEnv` (the arena's dynamics, wheel limits and distributed barrier), every agent
of every swarm one sub-environment of one shared policy (parameter sharing, as MARBLER's and VMAS's baselines),
trains PPO (Schulman et al., 2017; Raffin et al., JMLR 22(268), 2021) on CPU and returns the actor as a
:class:`~swarmdeck.envs.policy.Policy` — plain numpy weights, what the sandboxed experiment script loads.

Stable-Baselines3 and torch (CPU) are imported only here, on the trusted side that trains; nothing the arena runs
needs them. :class:`SwarmSB3VecEnv` is the batched env under SB3's ``VecEnv`` conventions (same-step autoreset,
``terminal_observation`` in the infos).
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.envs.batched import BatchedEnv, _action_space, _observation_space
from swarmdeck.envs.policy import Policy, make_policy
from swarmdeck.envs.scenarios import make_scenario

try:  # the optional extra: pip install 'swarmdeck[learn]'
    import stable_baselines3
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecEnv
except ImportError as _exc:  # pragma: no cover - exercised only without the extra
    raise ImportError("training needs the 'learn' extra: pip install 'swarmdeck[learn]' "
                      "(Stable-Baselines3 and a CPU build of torch)") from _exc

HIDDEN = (64, 64)  # SB3's default MlpPolicy actor: two tanh layers of 64


class SwarmSB3VecEnv(VecEnv):
    """E swarms × N agents of a :class:`BatchedEnv` as E·N sub-environments of SB3 (sub-environment ``e·N + i`` is
    agent i of swarm e; a swarm's end ends its N agents, which restart at once)."""

    def __init__(self, env: BatchedEnv) -> None:
        self.env = env
        self.n = env.n_envs * env.n_agents
        super().__init__(self.n, _observation_space(env), _action_space(env))
        self._actions: np.ndarray | None = None

    def reset(self) -> NDArray[np.float32]:
        seed = self._seeds[0] if self._seeds and self._seeds[0] is not None else None
        obs, _ = self.env.reset(seed=seed)
        self._reset_seeds()
        return obs.reshape(self.n, -1)

    def step_async(self, actions: np.ndarray) -> None:
        e, n = self.env.n_envs, self.env.n_agents
        a = np.asarray(actions)
        self._actions = a.reshape(e, n).astype(np.int64) if self.env.scenario.actions.kind == "moves" else a.reshape(e, n, 2)

    def step_wait(self) -> tuple[NDArray[np.float32], NDArray[np.float32], NDArray[np.bool_], list[dict[str, Any]]]:
        if self._actions is None:
            raise RuntimeError("step_async() before step_wait()")
        n = self.env.n_agents
        obs, rew, term, trunc, _ = self.env.step(self._actions)
        self._actions = None
        done = term | trunc
        infos: list[dict[str, Any]] = [{} for _ in range(self.n)]
        flat = obs.reshape(self.n, -1)
        if done.any():
            for k in np.flatnonzero(np.repeat(done, n)).tolist():
                infos[k] = {"terminal_observation": flat[k], "TimeLimit.truncated": bool(trunc[k // n] and not term[k // n])}
            flat = self.env.reset_done().reshape(self.n, -1)
        return flat, rew.reshape(-1).astype(np.float32), np.repeat(done, n), infos

    def close(self) -> None:
        return None

    def get_attr(self, attr_name: str, indices: Any = None) -> list[Any]:
        value = None if attr_name == "render_mode" else getattr(self.env, attr_name)  # nothing to render
        return [value] * len(self._indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: Any = None) -> None:
        setattr(self.env, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any, indices: Any = None, **method_kwargs: Any) -> list[Any]:
        return [getattr(self.env, method_name)(*method_args, **method_kwargs)] * len(self._indices(indices))

    def env_is_wrapped(self, wrapper_class: type, indices: Any = None) -> list[bool]:
        return [False] * len(self._indices(indices))

    def _indices(self, indices: Any) -> list[int]:
        if indices is None:
            return list(range(self.n))
        return [indices] if isinstance(indices, int) else list(indices)


def ppo(scenario: str, *, n_agents: int | None = None, n_envs: int = 8, seed: int = 0, steps: int = 20000,
        hidden: Sequence[int] = HIDDEN, safety: bool = True) -> PPO:
    """An untrained SB3 PPO (MlpPolicy, tanh, CPU, one torch thread, seeded) on ``n_envs`` swarms of the shipped
    ``scenario`` with ``n_agents`` robots each (default: the scenario's), its rollout sized for ``steps``
    agent-steps of training. ValueError for an unknown scenario or bad sizes."""
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise ValueError(f"steps must be an int >= 1, got {steps!r}")
    if isinstance(n_envs, bool) or not isinstance(n_envs, int) or n_envs < 1:
        raise ValueError(f"n_envs must be an int >= 1 (swarms stepped at once), got {n_envs!r}")
    widths = [int(h) for h in hidden]
    if not widths or any(h < 1 for h in widths):
        raise ValueError(f"hidden must be one or more layer widths >= 1, got {list(hidden)!r}")
    args: dict[str, Any] = {} if n_agents is None else {"n_agents": int(n_agents)}
    venv = SwarmSB3VecEnv(BatchedEnv(make_scenario(scenario, **args), n_envs, safety=safety))
    rollout = int(max(8, min(256, steps // venv.num_envs)))  # steps per sub-environment between updates
    batch = int(min(256, rollout * venv.num_envs))
    torch.set_num_threads(1)
    return PPO("MlpPolicy", venv, n_steps=rollout, batch_size=batch, seed=seed, device="cpu", verbose=0,
               policy_kwargs={"net_arch": {"pi": widths, "vf": widths}, "activation_fn": torch.nn.Tanh})


def train(scenario: str, *, steps: int, n_agents: int | None = None, n_envs: int = 8, seed: int = 0,
          hidden: Sequence[int] = HIDDEN, safety: bool = True,
          progress: Callable[[str], None] | None = None) -> Policy:
    """Train PPO for ``steps`` agent-steps (SB3's ``total_timesteps``: every agent of every swarm counts; rounded up
    to whole rollouts) on ``n_envs`` swarms of the shipped ``scenario`` (``n_agents`` robots each, default the
    scenario's; :func:`ppo`) and return the trained actor as a numpy :class:`Policy`. The same arguments give the
    same policy on one machine. ValueError for an unknown scenario or bad sizes."""
    model = ppo(scenario, n_agents=n_agents, n_envs=n_envs, seed=seed, steps=steps, hidden=hidden, safety=safety)
    env = model.get_env()
    assert isinstance(env, SwarmSB3VecEnv)
    sc = env.env.scenario
    if progress is not None:
        progress(f"training PPO on {scenario} ({n_envs} swarms x {sc.n_agents} robots, {steps} agent-steps)")
    model.learn(total_timesteps=steps)
    return export_actor(model, scenario, {"n_agents": sc.n_agents},
                        trained={"library": f"stable-baselines3 {stable_baselines3.__version__}", "algorithm": "PPO",
                                 "steps": int(model.num_timesteps), "seed": seed, "n_envs": n_envs,
                                 "safety": safety})


def export_actor(model: Any, scenario: str, scenario_args: dict[str, Any], trained: dict[str, Any]) -> Policy:
    """The deterministic actor of an SB3 PPO ``MlpPolicy`` (flatten → tanh MLP → action net) as a numpy
    :class:`Policy`; ValueError for another architecture."""
    pol = model.policy
    linears = [m for m in pol.mlp_extractor.policy_net if isinstance(m, torch.nn.Linear)]
    others = [m for m in pol.mlp_extractor.policy_net if not isinstance(m, (torch.nn.Linear, torch.nn.Tanh))]
    if others or not isinstance(pol.action_net, torch.nn.Linear):
        raise ValueError("only an MlpPolicy with tanh layers can be exported")
    layers = [(m.weight.detach().cpu().numpy().T.copy(), m.bias.detach().cpu().numpy().copy())
              for m in [*linears, pol.action_net]]
    space = model.action_space
    discrete = hasattr(space, "n")
    low = [0.0, 0.0] if discrete else np.asarray(space.low, dtype=float)
    high = [0.0, 0.0] if discrete else np.asarray(space.high, dtype=float)
    kind = make_scenario(scenario, **scenario_args).actions.kind
    return make_policy(layers, scenario=scenario, scenario_args=scenario_args, action=kind, action_low=low,
                       action_high=high, activation="tanh", trained=trained)
