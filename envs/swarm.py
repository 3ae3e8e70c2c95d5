"""A PettingZoo ``ParallelEnv`` of the simulated arena: one agent per robot, every action through the safety filter.

Built on the public experiment API (:class:`swarmdeck.devices.Arena`): each
:meth:`SwarmParallelEnv.step` sets every robot's command at the level chosen by
``action`` and calls ``Arena.step()``, which applies the wheel limits (one
scale per robot) and the barrier-certificate filter (on unless
``safety=False``), exactly as an experiment on the arena would. Conventions
(REFERENCE.md §14): ``reset(seed=…) -> (observations, infos)``,
``step(actions) -> (observations, rewards, terminations, truncations, infos)``,
per-agent ``observation_space(agent)`` / ``action_space(agent)``; agents are
``"robot_0" … "robot_{N-1}"``; episodes end by truncation after ``max_steps``
(no robot ever terminates on its own).

Actions (float32, clipped to the space):

* ``"velocity"`` — (u_x, u_y) m/s, the single-integrator velocity of the robot's
  look-ahead point, |u| components ≤ 0.2 m/s (``Arena.set_velocities``);
* ``"unicycle"`` — (v m/s, ω rad/s) within the wheel limits' box (``Arena.set_unicycle``).

An action with the wrong shape or a NaN/inf entry is a ``ValueError`` naming
the agent and the shape; an agent missing from the dict stands still.

Infos (per agent): ``filter_change`` — ‖u*_i − û_i‖ (m/s), how much the barrier
filter changed this robot's command (0 with ``safety=False``); ``command_change`` —
how much the whole pipeline (wheel limits and filter) changed it, m/s;
``filter_active`` (bool); ``filter_status``; ``min_distance`` between robots (m).

Observations: :mod:`swarmdeck.envs.observations`. Rewards: :mod:`swarmdeck.envs.tasks`.
Seeds: ``reset(seed=s)`` draws the initial poses (and the coverage density's
bumps) from ``numpy.random.default_rng(s)``; the simulation itself is
deterministic, so equal seeds and actions give equal episodes.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.constants import CONTROL_PERIOD
from swarmdeck.envs.neighbours import min_distance
from swarmdeck.envs.observations import observation_bounds, observation_size, observe, tof_block
from swarmdeck.envs.tasks import (
    TASKS,
    coverage_cells,
    coverage_reward,
    formation_reward,
    formation_slots,
    rendezvous_reward,
)
from swarmdeck.sensing import DistanceSensorConfig, SensingConfig

try:  # the optional extra: pip install 'swarmdeck[rl]'
    from gymnasium import spaces
    from pettingzoo import ParallelEnv
except ImportError as _exc:  # pragma: no cover - exercised only without the extra
    raise ImportError("swarmdeck.envs needs the 'rl' extra: pip install 'swarmdeck[rl]'") from _exc

ACTIONS = ("velocity", "unicycle")
BARRIERS = ("centralised", "distributed")


@dataclass(frozen=True)
class EnvConfig:
    """Configuration of :class:`SwarmParallelEnv` (defaults: REFERENCE.md §1).

    n_robots: N ≥ 1. task: "coverage" | "formation" | "rendezvous". action: "velocity" | "unicycle".
    k_neighbours: neighbours observed (≥ 0). density_obs: add the local density to observations.
    safety: the barrier filter on every action (True) or off. max_steps: steps per episode.
    bounds: arena (x_min, x_max, y_min, y_max), m. dt: control period, s.
    formation_radius: m. n_bumps: Gaussian bumps of the coverage density (drawn per episode).
    barrier: "centralised" (one QP over the swarm) or "distributed" (every robot its own QP, REFERENCE.md §12;
        what the batched environment runs, :mod:`swarmdeck.envs.batched`).
    sensors: the robots' ToF distance sensors (:class:`~swarmdeck.sensing.DistanceSensorConfig`, e.g. the
        Robotarium 2.0's seven) as an optional observation block (their readings / range), None: none. The noise
        is seeded from ``reset(seed)``.
    """

    n_robots: int = 6
    task: str = "coverage"
    action: str = "velocity"
    k_neighbours: int = 3
    density_obs: bool = False
    safety: bool = True
    max_steps: int = 600
    bounds: Bounds = DEFAULT_BOUNDS
    dt: float = CONTROL_PERIOD
    formation_radius: float = 0.6
    n_bumps: int = 2
    barrier: str = "centralised"
    sensors: DistanceSensorConfig | None = None

    def __post_init__(self) -> None:
        def intlike(v: Any) -> bool:
            return isinstance(v, (int, np.integer)) and not isinstance(v, bool)

        if not (intlike(self.n_robots) and self.n_robots >= 1):
            raise ValueError(f"n_robots must be an int >= 1, got {self.n_robots!r}")
        if self.task not in TASKS:
            raise ValueError(f"task must be one of {TASKS}, got {self.task!r}")
        if self.action not in ACTIONS:
            raise ValueError(f"action must be one of {ACTIONS}, got {self.action!r}")
        if not (intlike(self.k_neighbours) and self.k_neighbours >= 0):
            raise ValueError(f"k_neighbours must be an int >= 0, got {self.k_neighbours!r}")
        if not (intlike(self.max_steps) and self.max_steps >= 1):
            raise ValueError(f"max_steps must be an int >= 1, got {self.max_steps!r}")
        if not (intlike(self.n_bumps) and self.n_bumps >= 1):
            raise ValueError(f"n_bumps must be an int >= 1, got {self.n_bumps!r}")
        if not (math.isfinite(self.formation_radius) and self.formation_radius > 0):
            raise ValueError(f"formation_radius must be > 0 m, got {self.formation_radius!r}")
        if self.barrier not in BARRIERS:
            raise ValueError(f"barrier must be one of {BARRIERS}, got {self.barrier!r}")
        if self.sensors is not None and not isinstance(self.sensors, DistanceSensorConfig):
            raise ValueError(f"sensors must be a DistanceSensorConfig or None, got {self.sensors!r}")
        if self.density_obs and self.task != "coverage":
            raise ValueError("density_obs needs task='coverage' (the other tasks have no density)")


class SwarmParallelEnv(ParallelEnv):
    """PettingZoo parallel environment of N GRITSBots (see the module docstring)."""

    metadata = {"render_modes": [], "name": "swarmdeck_swarm_v0", "is_parallelizable": True}

    def __init__(self, config: EnvConfig | None = None) -> None:
        from swarmdeck.devices import GritsBotParams

        self.config = cfg = config or EnvConfig()
        self.render_mode = None
        self.params = GritsBotParams()
        self.possible_agents = [f"robot_{i}" for i in range(cfg.n_robots)]
        self.agents: list[str] = []
        self._index = {a: i for i, a in enumerate(self.possible_agents)}
        self._k_tof = 0 if cfg.sensors is None else cfg.sensors.n_sensors
        lo, hi = observation_bounds(cfg.k_neighbours, cfg.task, cfg.density_obs, cfg.bounds, self._k_tof)
        self._obs_lo, self._obs_hi = lo, hi
        self._obs_space = {a: spaces.Box(lo, hi, dtype=np.float32) for a in self.possible_agents}
        if cfg.action == "velocity":
            s = self.params.max_speed
            alo, ahi = np.array([-s, -s], dtype=np.float32), np.array([s, s], dtype=np.float32)
        else:
            w_max = 2.0 * self.params.max_wheel_speed * self.params.wheel_radius / self.params.axle_length
            alo = np.array([-self.params.max_speed, -w_max], dtype=np.float32)
            ahi = -alo
        self._act_lo, self._act_hi = alo, ahi
        self._act_space = {a: spaces.Box(alo, ahi, dtype=np.float32) for a in self.possible_agents}
        self._rng: np.random.Generator | None = None
        self.arena: Any = None
        self.density: Any = None
        self.slots = formation_slots(cfg.n_robots, cfg.formation_radius,
                                     ((cfg.bounds[0] + cfg.bounds[1]) / 2, (cfg.bounds[2] + cfg.bounds[3]) / 2))
        self.steps = 0
        self.moments: Any = None
        self._density_scale = 1.0
        assert observation_size(cfg.k_neighbours, cfg.task, cfg.density_obs, self._k_tof) == len(lo)

    # ------------------------------------------------------------------ spaces
    def observation_space(self, agent: str) -> spaces.Box:
        return self._obs_space[agent]

    def action_space(self, agent: str) -> spaces.Box:
        return self._act_space[agent]

    # ------------------------------------------------------------------ episode
    def _draw_density(self) -> Any:
        from swarmdeck.coverage import GaussianMixture

        x0, x1, y0, y1 = self.config.bounds
        k = self.config.n_bumps
        rng = self._rng
        assert rng is not None, "reset() draws the generator first"
        mu = np.column_stack((rng.uniform(x0 + 0.3, x1 - 0.3, k), rng.uniform(y0 + 0.3, y1 - 0.3, k)))
        return GaussianMixture(floor=0.05, mu=mu, sigma=rng.uniform(0.2, 0.4, k), weight=rng.uniform(0.5, 1.0, k))

    def reset(self, seed: int | None = None, options: dict | None = None
              ) -> tuple[dict[str, NDArray[np.float32]], dict[str, dict[str, Any]]]:
        """Start an episode: random non-overlapping poses (and density) from ``seed``."""
        from swarmdeck.devices import Arena, ArenaConfig, random_initial_poses

        cfg = self.config
        if seed is not None or self._rng is None:
            self._rng = np.random.default_rng(seed)
        poses = random_initial_poses(cfg.n_robots, cfg.bounds, rng=self._rng)
        self.density = self._draw_density() if cfg.task == "coverage" else None
        if self.density is not None:
            self._density_scale = float(self.density.evaluate(self.density.mu).max()) or 1.0
        self.arena = Arena(initial_conditions=poses, config=ArenaConfig(bounds=cfg.bounds, dt=cfg.dt),
                           params=self.params, safety=self._safety())
        if cfg.sensors is not None:
            self.arena.use_sensors(SensingConfig(distance=cfg.sensors, imu=None, leds=False),
                                   seed=int(self._rng.integers(2**31)))
        self.agents = list(self.possible_agents)
        self.steps = 0
        self.moments = None
        n = cfg.n_robots
        infos = self._infos(np.zeros(n), np.zeros(n), "reset", True)
        return self._observations(), infos

    def _safety(self) -> Any:
        """The Arena's ``safety``: the barrier of ``config.barrier``, or off."""
        from swarmdeck.devices.pipeline import barrier_filter

        cfg = self.config
        if not cfg.safety or cfg.barrier == "centralised":
            return cfg.safety
        return barrier_filter(self.params, cfg.bounds, cfg.dt, mode="distributed")

    def _observations(self) -> dict[str, NDArray[np.float32]]:
        poses = self.arena.poses()
        obs = observe(poses, self.arena.positions(), self.config.bounds, self.config.k_neighbours,
                      self.slots if self.config.task == "formation" else None,
                      self.density if self.config.density_obs else None, density_scale=self._density_scale)
        if self.config.sensors is not None:  # the robots' own ToF readings (optional block, last)
            obs = np.concatenate((obs, tof_block(self.arena.sense().distances, self.config.sensors.max_range)), axis=1)
        obs = np.clip(obs, self._obs_lo, self._obs_hi)
        return {a: obs[i] for i, a in enumerate(self.possible_agents)}

    def _actions(self, actions: dict[str, Any]) -> NDArray[np.float64]:
        n = self.config.n_robots
        out = np.zeros((n, 2))
        for agent, act in actions.items():
            i = self._index.get(agent)
            if i is None:
                raise ValueError(f"unknown agent {agent!r} (agents are robot_0 … robot_{n - 1})")
            a = np.asarray(act, dtype=float) if not isinstance(act, str) else None
            if a is None or a.shape != (2,):
                got = "a string" if a is None else f"shape {a.shape}"
                raise ValueError(f"action of agent {agent!r} must have shape (2,) ({self.config.action}), got {got}")
            if not np.all(np.isfinite(a)):
                raise ValueError(f"action of agent {agent!r} (shape (2,)) contains NaN or inf: {a.tolist()}")
            out[i] = a
        return np.clip(out, self._act_lo, self._act_hi)

    def _infos(self, filter_change: NDArray[np.float64], command_change: NDArray[np.float64], status: str,
               ok: bool) -> dict[str, dict[str, Any]]:
        from swarmdeck.core.kinematics import lookahead_points

        dmin = min_distance(lookahead_points(self.arena.poses(), self.params.lookahead))
        return {a: {"filter_change": float(filter_change[i]), "command_change": float(command_change[i]),
                    "filter_active": bool(filter_change[i] > 1e-9), "filter_status": status, "filter_ok": ok,
                    "min_distance": dmin}
                for i, a in enumerate(self.possible_agents)}

    def step(self, actions: dict[str, Any]) -> tuple[dict[str, Any], dict[str, float], dict[str, bool],
                                                     dict[str, bool], dict[str, dict[str, Any]]]:
        """Apply one action per agent through the safety filter and advance one period (``dt``)."""
        if not self.agents:
            raise RuntimeError("the episode is over (or was never started): call reset()")
        act = self._actions(actions)
        arena = self.arena
        if self.config.action == "velocity":
            arena.set_velocities(act)
        else:
            arena.set_unicycle(act[:, 0], act[:, 1])
        arena.step()
        self.steps += 1
        n = self.config.n_robots
        diag = arena.safety_stats.last_diagnostics if self.config.safety else None
        inter = np.asarray(getattr(diag, "intervention", np.zeros(n)), dtype=float) if diag is not None else np.zeros(n)
        if inter.shape != (n,):
            inter = np.zeros(n)
        command_change = np.linalg.norm(arena.last_safe - arena.last_nominal, axis=1)
        status = str(getattr(diag, "status", "ok")) if diag is not None else "off"
        ok = bool(getattr(diag, "ok", True)) if diag is not None else True
        rewards_arr = self._rewards()
        truncated = self.steps >= self.config.max_steps
        obs = self._observations()
        infos = self._infos(inter, command_change, status, ok)
        rewards = {a: float(rewards_arr[i]) for i, a in enumerate(self.possible_agents)}
        terminations = {a: False for a in self.agents}
        truncations = {a: truncated for a in self.agents}
        if truncated:
            self.agents = []
        return obs, rewards, terminations, truncations, infos

    def _rewards(self) -> NDArray[np.float64]:
        pts = self.arena.positions()
        task = self.config.task
        if task == "rendezvous":
            return rendezvous_reward(pts)
        if task == "formation":
            return formation_reward(pts, self.slots)
        try:
            self.moments = coverage_cells(pts, self.density, self.config.bounds)
        except (RuntimeError, ValueError) as exc:  # a degenerate diagram: no reward signal this step
            self.moments = None
            self.arena.events.append(f"coverage cells failed: {exc}")
            return np.zeros(len(pts))
        return coverage_reward(self.moments)

    def state(self) -> NDArray[np.float32]:
        """The global state: every robot's pose [x, y, θ], flattened (N·3,)."""
        return self.arena.poses().astype(np.float32).reshape(-1)

    def render(self) -> None:
        """No built-in rendering: record episodes (``swarmdeck.console.recording.episodes``) and play them."""
        return None

    def close(self) -> None:
        self.arena = None


def parallel_env(n_robots: int = 6, task: str = "coverage", **kwargs: Any) -> SwarmParallelEnv:
    """PettingZoo's constructor convention: ``swarmdeck.envs.parallel_env(n_robots=10, task="formation")``.
    Keyword arguments are the fields of :class:`EnvConfig`."""
    return SwarmParallelEnv(EnvConfig(n_robots=n_robots, task=task, **kwargs))
