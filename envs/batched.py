"""A batched environment for learning: E copies of a scenario stepped at once on the simulated arena.

    from swarmdeck.envs import BatchedEnv, scenarios
    env = BatchedEnv(scenarios.Rendezvous(n_agents=10), n_envs=64)
    obs, info = env.reset(seed=0)                  # obs (E, N, D); swarm e seeded with seed + e
    obs, rew, term, trunc, info = env.step(act)    # act (E, N, 2) or (E, N) ints; rew (E, N); term/trunc (E,)

Each step holds every agent's action for ``scenario.actions.hold`` ticks of
:class:`~swarmdeck.envs.batched_swarm.BatchedSwarm` (the arena's pipeline and the distributed
barrier, bit for bit), then calls the scenario's hooks (:mod:`swarmdeck.envs.scenario`). A swarm
whose episode ended (terminated or truncated) is reset at its next step (Gymnasium's "next step"
autoreset): that step returns its first observation, zero reward and no termination.

Conventions: :class:`SwarmVectorEnv` is a ``gymnasium.vector.VectorEnv`` of E·N agents sharing one
policy (SuperSuit's convention for parameter sharing: one sub-environment per agent);
:class:`ScenarioParallelEnv` is one swarm as a PettingZoo ``ParallelEnv`` (agents named by kind).

Infos (arrays): ``filter_change`` and ``command_change`` (E, N) m/s, summed over the held ticks
(see :class:`~swarmdeck.envs.batched_swarm.TickResult`); ``filter_ok`` (E,) every tick certified;
``violation`` (E,) "", "collision", "boundary" or "collision_boundary" (the tick it happened ends the
step for that swarm); ``min_distance`` (E,) between look-ahead points, m; ``reset`` (E,) swarms reset
by this call.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.constants import CONTROL_PERIOD
from swarmdeck.devices.controllers import si_position_controller
from swarmdeck.devices.simulator import check_poses
from swarmdeck.envs.batched_swarm import BatchedSwarm
from swarmdeck.envs.scenario import Scenario, State, View, goal_points

try:  # the optional extra: pip install 'swarmdeck[rl]'
    import gymnasium
    from gymnasium import spaces
    from pettingzoo import ParallelEnv
except ImportError as _exc:  # pragma: no cover - exercised only without the extra
    raise ImportError("swarmdeck.envs needs the 'rl' extra: pip install 'swarmdeck[rl]'") from _exc

FloatArray = NDArray[np.float64]


class BatchedEnv:
    """E swarms of one scenario (module docstring). ``safety``: the distributed barrier on every tick;
    ``dt``: control period, s."""

    def __init__(self, scenario: Scenario, n_envs: int = 1, *, safety: bool = True, dt: float = CONTROL_PERIOD) -> None:
        self.scenario = sc = scenario
        self.sim = BatchedSwarm(n_envs, sc.n_agents, bounds=sc.bounds, dt=dt, safety=safety)
        self.n_envs, self.n_agents = self.sim.n_swarms, sc.n_agents
        params = self.sim.params
        if sc.actions.kind == "velocity":
            s = params.max_speed
            self.action_low = np.array([-s, -s], dtype=np.float32)
            self.action_high = -self.action_low
        else:
            x0, x1, y0, y1 = sc.actions.box or sc.bounds
            self.action_low = np.array([x0, y0], dtype=np.float32)
            self.action_high = np.array([x1, y1], dtype=np.float32)
        self._act_lo, self._act_hi = self.action_low.astype(float), self.action_high.astype(float)
        self.obs_low, self.obs_high = (np.asarray(b, dtype=np.float32) for b in sc.observation_bounds())
        self._rngs: list[np.random.Generator] = []
        self.state: State = {}
        self.steps = np.zeros(self.n_envs, dtype=np.int64)
        self._done = np.zeros(self.n_envs, dtype=bool)
        self._last_actions = self._zero_actions(self.n_envs)

    # ------------------------------------------------------------------ episodes
    def _zero_actions(self, e: int) -> np.ndarray:
        if self.scenario.actions.kind == "moves":
            return np.full((e, self.n_agents), 4, dtype=np.int64)
        return np.zeros((e, self.n_agents, 2))

    def reset(self, seed: int | None = None, options: dict | None = None) -> tuple[NDArray[np.float32], dict[str, Any]]:
        """Start every swarm: swarm e draws from ``numpy.random.default_rng(seed + e)`` (or fresh entropy)."""
        seeds = np.random.SeedSequence(None).spawn(self.n_envs) if seed is None else [seed + e for e in range(self.n_envs)]
        self._rngs = [np.random.default_rng(s) for s in seeds]
        self._reset_swarms(np.arange(self.n_envs))
        self._done = np.zeros(self.n_envs, dtype=bool)  # a new array: earlier infos' "reset" keep theirs
        info = {"reset": np.ones(self.n_envs, dtype=bool)}
        return self._observe(), info

    def _reset_swarms(self, which: NDArray[np.intp]) -> None:
        starts = [self.scenario.reset(self._rngs[e]) for e in which]
        starts = [(check_poses(p, f"{type(self.scenario).__name__}.reset poses", self.n_agents), s) for p, s in starts]
        self.sim.set_poses(np.stack([p for p, _ in starts]), which)
        state = {k: v.copy() for k, v in self.state.items()} if self.state else {}
        for key in starts[0][1] if starts else ():
            rows = np.stack([np.asarray(s[key]) for _, s in starts])
            if key not in state or len(which) == self.n_envs:
                state[key] = np.zeros((self.n_envs, *rows.shape[1:]), dtype=rows.dtype)
            state[key][which] = rows
        self.state = state
        self.steps = np.where(np.isin(np.arange(self.n_envs), which), 0, self.steps)
        last = self._last_actions.copy()
        last[which] = self._zero_actions(len(which))
        self._last_actions = last

    def reset_done(self) -> NDArray[np.float32]:
        """Start now the swarms whose episode the last step ended (same-step autoreset, Stable-Baselines3's VecEnv
        convention, instead of on the next step); returns every swarm's observation (E, N, D)."""
        restart = np.flatnonzero(self._done)
        if restart.size:
            self._reset_swarms(restart)
            done = self._done.copy()
            done[restart] = False
            self._done = done
        return self._observe()

    def _view(self) -> View:
        return View(self.sim.poses, self.sim.points(), self.state, self._last_actions, self.steps, self.scenario.bounds)

    def _observe(self, view: View | None = None) -> NDArray[np.float32]:
        obs = np.asarray(self.scenario.observe(self._view() if view is None else view), dtype=np.float32)
        return np.clip(obs, self.obs_low, self.obs_high)

    # ------------------------------------------------------------------ actions
    def _check_actions(self, actions: Any) -> np.ndarray:
        e, n = self.n_envs, self.n_agents
        kind = self.scenario.actions.kind
        if kind == "moves":
            a = np.asarray(actions)
            if a.shape != (e, n) or not np.issubdtype(a.dtype, np.integer) or np.any((a < 0) | (a > 4)):
                raise ValueError(f"actions must be ints 0..4 of shape ({e}, {n}) (moves: -x, +x, -y, +y, stay), "
                                 f"got {a.dtype} of shape {a.shape}")
            return a.astype(np.int64)
        a = np.asarray(actions, dtype=float)
        if a.shape != (e, n, 2):
            raise ValueError(f"actions must have shape ({e}, {n}, 2) ({kind}), got shape {a.shape}")
        if not np.isfinite(a).all():
            bad = np.argwhere(~np.all(np.isfinite(a), axis=2))[:5].tolist()
            raise ValueError(f"actions contain NaN or inf at (swarm, agent) {bad}")
        return np.minimum(np.maximum(a, self._act_lo), self._act_hi)  # np.clip (finite), without its wrappers

    def _goals(self, actions: np.ndarray) -> FloatArray | None:
        act = self.scenario.actions
        if act.kind == "velocity":
            return None
        return goal_points(act, actions, self.sim.poses[..., :2], self.scenario.bounds)

    # ------------------------------------------------------------------ the step
    def step(self, actions: Any) -> tuple[NDArray[np.float32], FloatArray, NDArray[np.bool_], NDArray[np.bool_],
                                          dict[str, Any]]:
        """Hold each agent's action for ``hold`` ticks, then observe, reward and end episodes (module docstring).
        ``actions``: (E, N, 2) floats (velocity, goal) or (E, N) ints (moves); a wrong shape, a NaN or an unknown
        move is a ``ValueError`` naming it."""
        if not self._rngs:
            raise RuntimeError("call reset() before step()")
        act = self._check_actions(actions)
        e, n = self.n_envs, self.n_agents
        fresh = self._done  # swarms whose episode ended: reset now, they do not move this step
        any_fresh = bool(fresh.any())
        if any_fresh:
            self._reset_swarms(np.flatnonzero(fresh))
        sc = self.scenario
        goals = self._goals(act)
        check = sc.violation_penalty is not None
        live = ~fresh
        everyone = not any_fresh  # every swarm moves (the common case: no masking)
        code = np.zeros(e, dtype=np.int8)  # violations: 1 collision, 2 boundary, 3 both (_VIOLATIONS)
        filter_change = np.zeros((e, n))
        command_change = np.zeros((e, n))
        filter_ok = np.ones(e, dtype=bool)
        for _ in range(sc.actions.hold):
            if not everyone and not live.any():
                break
            nominal = act if goals is None else si_position_controller(
                self.sim.points().reshape(-1, 2), goals.reshape(-1, 2),
                speed_limit=self.sim.params.max_speed).reshape(e, n, 2)
            before = self.sim.poses
            res = self.sim.tick(nominal if everyone else np.where(live[:, None, None], nominal, 0.0), check=check)
            if everyone:
                filter_change += res.filter_change
                command_change += res.command_change
                filter_ok &= res.filter_ok
            else:  # swarms that are over (or start afresh) stay where they are
                self.sim.set_poses(np.where(live[:, None, None], self.sim.poses, before))
                filter_change += np.where(live[:, None], res.filter_change, 0.0)
                command_change += np.where(live[:, None], res.command_change, 0.0)
                filter_ok &= res.filter_ok | ~live
            if check:
                hit = live & (res.collision | res.boundary)
                if hit.any():
                    code[hit] = res.collision[hit].astype(np.int8) + 2 * res.boundary[hit].astype(np.int8)
                    live = live & ~hit
                    everyone = False
        steps = self.steps + 1
        if any_fresh:
            steps[fresh] = 0
            last = self._last_actions.copy()
            last[~fresh] = act[~fresh]
        else:
            last = act  # a new array (_check_actions)
        self.steps = steps
        self._last_actions = last
        view = self._view()
        rewards, state = sc.reward(view)
        violated = code != 0
        any_violated = bool(violated.any())
        if state and any_violated:  # a violating swarm keeps its state
            self.state = {k: np.where(_rows(violated, v), self.state[k], v) for k, v in state.items()}
        else:
            self.state = dict(state) if state else state
        rewards = np.array(rewards, dtype=float)
        if any_violated:
            rewards[violated] = sc.violation_penalty or 0.0
        if any_fresh:
            rewards[fresh] = 0.0
        view = view.with_state(self.state)
        terminated = violated | np.asarray(sc.terminated(view), dtype=bool)
        truncated = (steps >= sc.max_steps) & ~terminated
        if any_fresh:
            terminated &= ~fresh
            truncated &= ~fresh
        self._done = terminated | truncated
        obs = self._observe(view)  # before the minimum distance: it reuses the observation's neighbour query
        info = {"filter_change": filter_change, "command_change": command_change, "filter_ok": filter_ok,
                "violation": _VIOLATIONS[code], "min_distance": _min_distance(view), "reset": fresh}
        return obs, rewards, terminated, truncated, info


_VIOLATIONS = np.array(["", "collision", "boundary", "collision_boundary"])  # info["violation"] by code
_VIOLATIONS.setflags(write=False)


def _min_distance(view: View) -> FloatArray:
    """(E,) smallest distance between two look-ahead points of each swarm, m (inf for one robot)."""
    e, n, _ = view.points.shape
    return view.nearest_points(1)[0][..., 0].min(axis=1) if n > 1 else np.full(e, np.inf)


def _rows(mask: NDArray[np.bool_], like: np.ndarray) -> NDArray[np.bool_]:
    """``mask`` (E,) shaped to broadcast against ``like`` (E, …)."""
    return mask.reshape(mask.shape + (1,) * (like.ndim - 1))


# ---------------------------------------------------------------------------- conventions
def _action_space(env: BatchedEnv) -> spaces.Space:
    if env.scenario.actions.kind == "moves":
        return spaces.Discrete(5)
    return spaces.Box(env.action_low, env.action_high, dtype=np.float32)


def _observation_space(env: BatchedEnv) -> spaces.Box:
    return spaces.Box(env.obs_low, env.obs_high, dtype=np.float32)


class SwarmVectorEnv(gymnasium.vector.VectorEnv):
    """Gymnasium vector env of E·N agents sharing one policy: sub-environment ``e·N + i`` is agent i of swarm e;
    rewards per agent, terminations/truncations of its swarm; next-step autoreset (module docstring)."""

    metadata = {"autoreset_mode": gymnasium.vector.AutoresetMode.NEXT_STEP}

    def __init__(self, scenario: Scenario, n_envs: int = 1, **kwargs: Any) -> None:
        self.env = BatchedEnv(scenario, n_envs, **kwargs)
        self.num_envs = self.env.n_envs * self.env.n_agents
        self.single_observation_space = _observation_space(self.env)
        self.single_action_space = _action_space(self.env)
        self.observation_space = gymnasium.vector.utils.batch_space(self.single_observation_space, self.num_envs)
        self.action_space = gymnasium.vector.utils.batch_space(self.single_action_space, self.num_envs)
        self.render_mode = None

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[NDArray[np.float32], dict]:
        obs, _ = self.env.reset(seed=seed, options=options)
        return obs.reshape(self.num_envs, -1), {}

    def step(self, actions: Any) -> tuple[NDArray[np.float32], FloatArray, NDArray[np.bool_], NDArray[np.bool_], dict]:
        e, n = self.env.n_envs, self.env.n_agents
        a = np.asarray(actions)
        a = a.reshape(e, n) if self.env.scenario.actions.kind == "moves" else a.reshape(e, n, 2)
        obs, rew, term, trunc, info = self.env.step(a)
        return (obs.reshape(self.num_envs, -1), rew.reshape(-1), np.repeat(term, n), np.repeat(trunc, n), {})


class ScenarioParallelEnv(ParallelEnv):
    """One swarm of a scenario as a PettingZoo ``ParallelEnv``: agents ``"{kind}_{i}"`` (``scenario.types``)."""

    metadata = {"render_modes": [], "name": "swarmdeck_scenario_v0", "is_parallelizable": True}

    def __init__(self, scenario: Scenario, **kwargs: Any) -> None:
        self.env = BatchedEnv(scenario, 1, **kwargs)
        self.possible_agents = [f"{kind}_{i}" for i, kind in enumerate(scenario.types)]
        self.agents: list[str] = []
        self.render_mode = None
        self._obs_space = _observation_space(self.env)
        self._act_space = _action_space(self.env)

    def observation_space(self, agent: str) -> spaces.Space:
        return self._obs_space

    def action_space(self, agent: str) -> spaces.Space:
        return self._act_space

    def _dict(self, rows: np.ndarray) -> dict[str, Any]:
        return {a: rows[i] for i, a in enumerate(self.possible_agents)}

    def reset(self, seed: int | None = None, options: dict | None = None) -> tuple[dict, dict]:
        obs, _ = self.env.reset(seed=seed, options=options)
        self.agents = list(self.possible_agents)
        return self._dict(obs[0]), {a: {} for a in self.agents}

    def step(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        if not self.agents:
            raise RuntimeError("the episode is over (or was never started): call reset()")
        moves = self.env.scenario.actions.kind == "moves"
        rows = np.full(self.env.n_agents, 4, dtype=np.int64) if moves else np.zeros((self.env.n_agents, 2))
        index = {a: i for i, a in enumerate(self.possible_agents)}
        for agent, act in actions.items():
            if agent not in index:
                raise ValueError(f"unknown agent {agent!r} (agents are {self.possible_agents})")
            rows[index[agent]] = act
        obs, rew, term, trunc, info = self.env.step(rows[None])
        agents = self.agents
        done = bool(term[0] or trunc[0])
        out = ({a: obs[0][index[a]] for a in agents}, {a: float(rew[0][index[a]]) for a in agents},
               {a: bool(term[0]) for a in agents}, {a: bool(trunc[0]) for a in agents},
               {a: {"violation": str(info["violation"][0])} for a in agents})
        if done:
            self.agents = []
        return out

    def state(self) -> NDArray[np.float32]:
        """Every robot's pose [x, y, θ], flattened (N·3,)."""
        return self.env.sim.poses[0].astype(np.float32).reshape(-1)

    def render(self) -> None:
        return None

    def close(self) -> None:
        return None
