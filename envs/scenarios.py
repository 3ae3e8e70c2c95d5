"""Scenarios shipped with swarmdeck (:mod:`swarmdeck.envs.scenario`): the learning tasks and two of MARBLER's.

* :class:`Rendezvous`, :class:`Formation` — the tasks of :mod:`swarmdeck.envs.tasks` with the observations of
  :mod:`swarmdeck.envs.observations`, velocity actions: swarm e of a :class:`~swarmdeck.envs.batched.BatchedEnv`
  equals ``swarmdeck.envs.parallel_env(task=…, barrier="distributed")`` reset with ``seed + e``, bit for bit.
* :class:`PredatorCapturePrey`, :class:`Warehouse` — MARBLER's scenarios (Torbati et al., 2023,
  github.com/GT-STAR-Lab/MARBLER, commit 59c4923, ``robotarium_gym/scenarios``), their defaults from its
  ``config.yaml``: discrete moves of 0.2 m held for 29 ticks, −5 for every agent and the end of the episode on a
  collision or a boundary violation. Rewards are MARBLER's (checked on its own code, tests/envs/test_envs_scenarios_marbler.py).
  Differences: goals are driven by the arena's go-to-goal every tick (MARBLER recomputes every 15th) under
  swarmdeck's barrier; the reward is computed on the poses after the held step (MARBLER's on those one tick
  earlier); the start poses come from :func:`swarmdeck.devices.random_initial_poses` in MARBLER's regions.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.bounds import Bounds
from swarmdeck.envs import batched_kernels as kern
from swarmdeck.envs.observations import observation_bounds
from swarmdeck.envs.scenario import Actions, Scenario, State, View
from swarmdeck.envs.tasks import formation_slots

FloatArray = NDArray[np.float64]


# ---------------------------------------------------------------------------- swarmdeck's tasks
def task_observations(view: View, k: int, slots: FloatArray | None = None) -> NDArray[np.float32]:
    """(E, N, D) :func:`swarmdeck.envs.observations.observe` for E swarms at once (no density part); compiled
    (:func:`swarmdeck.envs.batched_kernels.task_observations`, the same bits) when numba is installed."""
    poses, points = view.poses, view.points
    e, n, _ = poses.shape
    x0, x1, y0, y1 = view.bounds
    kk = min(k, n - 1)
    cos_t, sin_t = np.cos(poses[..., 2:3]), np.sin(poses[..., 2:3])
    if kern.use_compiled(e * n):
        idx = view.nearest_points(kk)[1] if kk > 0 else np.zeros((e, n, 0), dtype=np.intp)
        out = np.empty((e * n, 10 + 2 * k if slots is not None else 8 + 2 * k), dtype=np.float32)
        kern.task_observations(np.ascontiguousarray(poses).reshape(e * n, 3), cos_t.reshape(e * n),
                               sin_t.reshape(e * n), np.ascontiguousarray(points).reshape(e * n, 2),
                               np.ascontiguousarray(idx).reshape(e * n, kk), n, k, float(x0), float(x1), float(y0),
                               float(y1), np.zeros((0, 2)) if slots is None else np.ascontiguousarray(slots, float),
                               out)
        return out.reshape(e, n, -1)
    parts = [poses[..., :2], cos_t, sin_t]
    rel = np.zeros((e, n, k, 2))
    if kk > 0:
        idx = view.nearest_points(kk)[1]
        rel[:, :, :kk] = np.take_along_axis(points[:, None, :, :], idx[..., None], axis=2) - points[:, :, None, :]
    parts.append(rel.reshape(e, n, 2 * k))
    px, py = points[..., 0], points[..., 1]
    parts.append(np.stack((px - x0, x1 - px, py - y0, y1 - py), axis=-1))
    if slots is not None:
        parts.append(slots[None] - points)
    return np.concatenate(parts, axis=-1).astype(np.float32)


@dataclass(frozen=True)
class Rendezvous(Scenario):
    """r_i = −‖p_i − p̄‖ (m), p̄ the swarm's mean look-ahead point; ``k_neighbours`` observed."""

    k_neighbours: int = 3
    max_steps: int = 600

    def __post_init__(self) -> None:
        object.__setattr__(self, "obs_size", 8 + 2 * self.k_neighbours)
        super().__post_init__()

    def observation_bounds(self) -> tuple[FloatArray, FloatArray]:
        lo, hi = observation_bounds(self.k_neighbours, "rendezvous", False, self.bounds)
        return lo.astype(float), hi.astype(float)

    def observe(self, view: View) -> NDArray[np.float32]:
        return task_observations(view, self.k_neighbours)

    def reward(self, view: View) -> tuple[FloatArray, State]:
        p = view.points
        return -np.linalg.norm(p - p.mean(axis=1, keepdims=True), axis=2), view.state


@dataclass(frozen=True)
class Formation(Scenario):
    """r_i = −‖p_i − g_i‖ (m), g_i robot i's slot of a regular polygon of ``radius`` (m) centred on the floor."""

    k_neighbours: int = 3
    radius: float = 0.6
    max_steps: int = 600

    def __post_init__(self) -> None:
        object.__setattr__(self, "obs_size", 10 + 2 * self.k_neighbours)
        super().__post_init__()

    @property
    def slots(self) -> FloatArray:
        """(N, 2) the polygon's slots, m."""
        x0, x1, y0, y1 = self.bounds
        return formation_slots(self.n_agents, self.radius, ((x0 + x1) / 2, (y0 + y1) / 2))

    def observation_bounds(self) -> tuple[FloatArray, FloatArray]:
        lo, hi = observation_bounds(self.k_neighbours, "formation", False, self.bounds)
        return lo.astype(float), hi.astype(float)

    def observe(self, view: View) -> NDArray[np.float32]:
        return task_observations(view, self.k_neighbours, self.slots)

    def reward(self, view: View) -> tuple[FloatArray, State]:
        return -np.linalg.norm(view.points - self.slots[None], axis=2), view.state


# ---------------------------------------------------------------------------- MARBLER's
MARBLER_BOX = Bounds(-1.4, 1.4, -0.9, 0.9)  # LEFT, RIGHT, UP, DOWN of MARBLER's configs: goals stay inside, m


def _neighbour_rows(view: View, own: FloatArray, k: int) -> FloatArray:
    """(E, N, (k+1)·d): each agent's own row ``own`` (E, N, d) followed by its neighbours' rows (MARBLER)."""
    idx = view.neighbours(k)
    e, n, d = own.shape
    nb = np.take_along_axis(own[:, None, :, :], np.asarray(idx)[..., None], axis=2)  # (E, N, k', d)
    return np.concatenate((own, nb.reshape(e, n, -1)), axis=-1)


@dataclass(frozen=True)
class PredatorCapturePrey(Scenario):
    """MARBLER's PredatorCapturePrey: ``n_predators`` sense prey within ``predator_radius``, ``n_capture`` agents
    capture a sensed prey within ``capture_radius`` by staying (move 4). Shared reward per step:
    ``sense_reward`` per prey first sensed + ``capture_reward`` per prey captured + ``time_penalty``; the episode
    ends when every prey is captured or after ``max_steps``. Observation: own [x, y, nearest sensed prey x, y]
    ([−5, −5] if none) and the same of ``num_neighbors`` others (MARBLER's order)."""

    n_agents: int = 4
    actions: Actions = Actions("moves", hold=29, step=0.2, box=MARBLER_BOX)
    max_steps: int = 81  # MARBLER: episode_steps > max_episode_steps (80)
    violation_penalty: float | None = -5.0
    n_predators: int = 2
    n_prey: int = 6
    predator_radius: float = 0.45
    capture_radius: float = 0.25
    num_neighbors: int = 3
    sense_reward: float = 1.0
    capture_reward: float = 5.0
    time_penalty: float = -0.05
    agent_types: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        if not self.agent_types:
            object.__setattr__(self, "agent_types", ("predator",) * self.n_predators
                               + ("capture",) * (self.n_agents - self.n_predators))
        object.__setattr__(self, "obs_size", 4 * (min(self.num_neighbors, self.n_agents - 1) + 1))
        super().__post_init__()

    @property
    def sensing(self) -> FloatArray:
        """(N,) each agent's sensing radius, m (0 for capture agents)."""
        return np.where(np.array(self.types) == "predator", self.predator_radius, 0.0)

    @property
    def capturing(self) -> FloatArray:
        """(N,) each agent's capture radius, m (0 for predators)."""
        return np.where(np.array(self.types) == "capture", self.capture_radius, 0.0)

    def observation_bounds(self) -> tuple[FloatArray, FloatArray]:
        return np.full(self.obs_size, -5.0), np.full(self.obs_size, 3.0)

    def reset(self, rng: np.random.Generator) -> tuple[FloatArray, State]:
        from swarmdeck.devices import random_initial_poses

        x0, x1, y0, y1 = MARBLER_BOX
        poses = random_initial_poses(self.n_agents, Bounds(x0, -0.5, y0, y1), rng=rng, wall_margin=0.1)
        poses[:, 2] = 0.0
        prey = random_initial_poses(self.n_prey, Bounds(0.5, x1, y0, y1), rng=rng, wall_margin=0.05)[:, :2]
        return poses, {"prey": prey, "sensed": np.zeros(self.n_prey, dtype=bool),
                       "captured": np.zeros(self.n_prey, dtype=bool)}

    def _distances(self, view: View) -> FloatArray:
        d = view.poses[:, :, None, :2] - view.state["prey"][:, None, :, :]
        return np.linalg.norm(d, axis=-1)  # (E, N, M) agents × prey: M is the prey count, not N

    def observe(self, view: View) -> NDArray[np.float32]:
        dist = self._distances(view)
        seen = (dist <= self.sensing[None, :, None]) & ~view.state["captured"][:, None, :]
        near = np.argmin(np.where(seen, dist, np.inf), axis=2)
        prey = np.take_along_axis(view.state["prey"], near[..., None].repeat(2, axis=-1), axis=1)
        prey = np.where(seen.any(axis=2, keepdims=True), prey, -5.0)
        own = np.concatenate((view.poses[..., :2], prey), axis=-1)
        return _neighbour_rows(view, own, self.num_neighbors).astype(np.float32)

    def reward(self, view: View) -> tuple[FloatArray, State]:
        dist = self._distances(view)
        sensed0, captured0 = view.state["sensed"], view.state["captured"]
        open_ = ~captured0
        sensed = sensed0 | (open_ & np.any(dist <= self.sensing[None, :, None], axis=1))
        staying = (np.asarray(view.actions) == 4)[:, :, None]
        captured = captured0 | (open_ & sensed & np.any(staying & (dist <= self.capturing[None, :, None]), axis=1))
        r = ((sensed.sum(axis=1) - sensed0.sum(axis=1)) * self.sense_reward
             + (captured.sum(axis=1) - captured0.sum(axis=1)) * self.capture_reward + self.time_penalty)
        state = dict(view.state, sensed=sensed, captured=captured)
        return np.repeat(r[:, None].astype(float), self.n_agents, axis=1), state

    def terminated(self, view: View) -> NDArray[np.bool_]:
        return np.all(view.state["captured"], axis=1)


@dataclass(frozen=True)
class Warehouse(Scenario):
    """MARBLER's Warehouse: agents load on the right edge (x > 1.5 − ``goal_width``) and unload on the left
    (x < −1.5 + ``goal_width``), each in its colour's half (even agents green: unload y > 0, load y ≤ 0; odd
    agents red: the other way round); ``load_reward`` and ``unload_reward`` per agent. Observation: own
    [x, y, loaded] (as before this step's loading and unloading, as in MARBLER) and the same of ``num_neighbors``
    others."""

    n_agents: int = 6
    actions: Actions = Actions("moves", hold=29, step=0.2, box=MARBLER_BOX)
    max_steps: int = 101  # MARBLER: episode_steps > max_episode_steps (100)
    violation_penalty: float | None = -5.0
    num_neighbors: int = 5
    load_reward: float = 1.0
    unload_reward: float = 3.0
    goal_width: float = 0.5
    agent_types: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        if not self.agent_types:
            object.__setattr__(self, "agent_types", tuple("green" if i % 2 == 0 else "red"
                                                          for i in range(self.n_agents)))
        object.__setattr__(self, "obs_size", 3 * (min(self.num_neighbors, self.n_agents - 1) + 1))
        super().__post_init__()

    def observation_bounds(self) -> tuple[FloatArray, FloatArray]:
        return np.full(self.obs_size, -1.5), np.full(self.obs_size, 1.5)

    def reset(self, rng: np.random.Generator) -> tuple[FloatArray, State]:
        from swarmdeck.devices import random_initial_poses

        poses = random_initial_poses(self.n_agents, MARBLER_BOX, rng=rng, wall_margin=0.1,
                                     spacing=0.6, min_separation=0.3)
        return poses, {"loaded": np.zeros(self.n_agents, dtype=bool), "shown": np.zeros(self.n_agents, dtype=bool)}

    def observe(self, view: View) -> NDArray[np.float32]:
        # MARBLER observes before its reward updates ``loaded``: "shown" is the flag before this step's update
        own = np.concatenate((view.poses[..., :2], view.state["shown"][..., None].astype(float)), axis=-1)
        return _neighbour_rows(view, own, self.num_neighbors).astype(np.float32)

    def reward(self, view: View) -> tuple[FloatArray, State]:
        x, y = view.poses[..., 0], view.poses[..., 1]
        green = (np.array(self.types) == "green")[None, :]
        loaded = view.state["loaded"]
        upper = y > 0
        unload = loaded & (x < -1.5 + self.goal_width) & np.where(green, upper, ~upper)
        load = ~loaded & (x > 1.5 - self.goal_width) & np.where(green, ~upper, upper)
        r = np.where(unload, self.unload_reward, np.where(load, self.load_reward, 0.0))
        return r, dict(view.state, loaded=(loaded & ~unload) | load, shown=loaded)


#: The shipped scenarios by the name ``swarmdeck train`` and a policy file use.
SHIPPED: dict[str, type[Scenario]] = {"rendezvous": Rendezvous, "formation": Formation,
                                      "predator_capture_prey": PredatorCapturePrey, "warehouse": Warehouse}


def make_scenario(name: str, **kwargs: object) -> Scenario:
    """The shipped scenario ``name`` (:data:`SHIPPED`) with ``kwargs`` (e.g. ``n_agents=4``); ValueError naming an
    unknown scenario or argument."""
    if name not in SHIPPED:
        raise ValueError(f"unknown scenario {name!r}; the shipped scenarios are {', '.join(SHIPPED)}")
    try:
        return SHIPPED[name](**kwargs)  # type: ignore[arg-type]
    except TypeError as exc:
        raise ValueError(f"scenario {name!r}: {exc}") from None
