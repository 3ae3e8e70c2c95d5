"""The scenario API: a learning task as hooks, without writing an environment.

A :class:`Scenario` says what the agents see, what they are rewarded for and when an episode ends;
:class:`swarmdeck.envs.batched.BatchedEnv` steps E copies of it at once on the simulated arena (the
arena's dynamics, wheel limits and distributed barrier). Every hook works on whole batches — arrays
of shape (E, N, …) — and returns new arrays (never mutates its arguments).

Hooks (override in a subclass):

* :meth:`Scenario.reset` — one swarm's start from its own ``numpy.random.Generator``: poses (N, 3)
  and the scenario's state (a dict of arrays, e.g. prey positions); the env stacks them over swarms;
* :meth:`Scenario.observe` — ``(E, N, D)`` observations from a :class:`View`;
* :meth:`Scenario.reward` — ``(E, N)`` rewards and the new state (e.g. prey captured);
* :meth:`Scenario.terminated` — ``(E,)`` swarms whose episode ended.

Actions (:class:`Actions`): ``"velocity"`` (continuous look-ahead velocity (2,) m/s),
``"goal"`` (continuous goal point (2,) m) or ``"moves"`` (discrete: 0 −x, 1 +x, 2 −y, 3 +y,
4 stay; a goal ``step`` metres away, MARBLER's left/right/up/down/no_action), each held for
``hold`` ticks (goal actions drive to the goal with the arena's single-integrator go-to-goal).
Heterogeneous agents: :attr:`Scenario.agent_types` names each agent's kind (agents keep one
observation and action size). With ``violation_penalty`` set, a collision or a centre off the floor
during a step ends that swarm's episode at once with that reward for every agent (MARBLER's
``penalize_violations``).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Literal

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.envs.neighbours import batched_nearest_neighbours, batched_query, lifted_tree

FloatArray = NDArray[np.float64]
State = dict[str, np.ndarray]

MOVES = np.array([[-1.0, 0.0], [1.0, 0.0], [0.0, -1.0], [0.0, 1.0], [0.0, 0.0]])  # left, right, up, down, stay
MOVES.setflags(write=False)


@dataclass(frozen=True)
class Actions:
    """How agents act. kind: "velocity" (m/s, |components| ≤ the robot's max speed) | "goal" (m) | "moves"
    (discrete, 5). hold: ticks an action is held (≥ 1). step: metres per move. box: goals are clipped into
    (x_min, x_max, y_min, y_max), m (None: the floor)."""

    kind: Literal["velocity", "goal", "moves"] = "velocity"
    hold: int = 1
    step: float = 0.2
    box: Bounds | None = None

    def __post_init__(self) -> None:
        if self.kind not in ("velocity", "goal", "moves"):
            raise ValueError(f"Actions.kind must be 'velocity', 'goal' or 'moves', got {self.kind!r}")
        if isinstance(self.hold, bool) or not isinstance(self.hold, (int, np.integer)) or self.hold < 1:
            raise ValueError(f"Actions.hold must be an int >= 1 (ticks), got {self.hold!r}")
        if not (np.isfinite(self.step) and self.step > 0):
            raise ValueError(f"Actions.step must be > 0 m, got {self.step!r}")


def goal_points(actions: Actions, chosen: np.ndarray, centres: FloatArray, bounds: Bounds) -> FloatArray:
    """The goal points (…, 2) m of ``chosen`` goal actions ((…, 2) m, returned as they are) or moves ((…,) ints 0…4:
    ``actions.step`` metres from the robots' ``centres`` (…, 2) m), clipped into ``actions.box`` (else ``bounds``)."""
    if actions.kind == "goal":
        return chosen
    x0, x1, y0, y1 = actions.box or bounds
    goal = centres + actions.step * MOVES[chosen]
    return np.stack((np.clip(goal[..., 0], x0, x1), np.clip(goal[..., 1], y0, y1)), axis=-1)


@dataclass(frozen=True)
class View:
    """What the hooks see, per swarm. poses (E, N, 3) m/rad; points (E, N, 2) look-ahead points, m;
    state: the scenario's arrays (E, …); actions: the actions of the step just taken ((E, N) ints or
    (E, N, 2) floats; zeros after a reset); steps (E,) steps since the reset; bounds: the floor."""

    poses: FloatArray
    points: FloatArray
    state: State
    actions: np.ndarray
    steps: NDArray[np.int64]
    bounds: Bounds

    @cached_property
    def points_tree(self) -> cKDTree:
        """One k-d tree over every swarm's look-ahead points (:func:`swarmdeck.envs.neighbours.lifted_tree`), built once
        per view."""
        return lifted_tree(self.points)

    def nearest_points(self, k: int) -> tuple[FloatArray, NDArray[np.intp]]:
        """Each agent's k nearest other look-ahead points (k ≤ N − 1): distances (E, N, k) m and indices (E, N, k),
        nearest first (:func:`swarmdeck.envs.neighbours.batched_query`, compiled, no tree; one query per view, reused
        for smaller k)."""
        cached = self.__dict__.get("_nearest")
        if cached is None or cached[0].shape[2] < k:
            cached = batched_query(self.points, k, self.__dict__.get("points_tree"))  # a tree only if already made
            self.__dict__["_nearest"] = cached
        return cached[0][..., :k], cached[1][..., :k]

    def with_state(self, state: State) -> View:
        """The same view with another state (the k-d tree and its queries, once made, are kept)."""
        new = View(self.poses, self.points, state, self.actions, self.steps, self.bounds)
        for key in ("points_tree", "_nearest"):
            if key in self.__dict__:
                new.__dict__[key] = self.__dict__[key]
        return new

    def neighbours(self, k: int) -> NDArray[np.intp]:
        """(E, N, k) each agent's k nearest other agents (by centre), nearest first — or, when k ≥ N − 1, all the
        others in index order (MARBLER's convention)."""
        e, n, _ = self.poses.shape
        if k >= n - 1:
            cols = np.arange(n - 1, dtype=np.intp)
            others = cols[None, :] + (cols[None, :] >= np.arange(n)[:, None])  # row i: 0 … N−1 without i
            return np.broadcast_to(others, (e, n, n - 1))
        return batched_nearest_neighbours(np.ascontiguousarray(self.poses[..., :2]), k)


@dataclass(frozen=True)
class Scenario:
    """Base of every scenario (module docstring). Fields: n_agents; actions; obs_size (D); max_steps (steps
    per episode, then truncation); violation_penalty (None: violations do not end episodes); bounds (the
    floor, m); agent_types (N names, default all "robot")."""

    n_agents: int = 4
    actions: Actions = Actions()
    obs_size: int = 4
    max_steps: int = 100
    violation_penalty: float | None = None
    bounds: Bounds = DEFAULT_BOUNDS
    agent_types: tuple[str, ...] = field(default=())

    def __post_init__(self) -> None:
        if isinstance(self.n_agents, bool) or not isinstance(self.n_agents, (int, np.integer)) or self.n_agents < 1:
            raise ValueError(f"{type(self).__name__}: n_agents must be an int >= 1, got {self.n_agents!r}")
        if isinstance(self.max_steps, bool) or not isinstance(self.max_steps, (int, np.integer)) or self.max_steps < 1:
            raise ValueError(f"{type(self).__name__}: max_steps must be an int >= 1, got {self.max_steps!r}")
        if self.agent_types and len(self.agent_types) != self.n_agents:
            raise ValueError(f"{type(self).__name__}: agent_types names {len(self.agent_types)} agents, "
                             f"n_agents is {self.n_agents}")

    @property
    def types(self) -> tuple[str, ...]:
        """Each agent's kind (N,)."""
        return self.agent_types or ("robot",) * self.n_agents

    def observation_bounds(self) -> tuple[FloatArray, FloatArray]:
        """(low, high) of one observation (D,); default: unbounded."""
        return np.full(self.obs_size, -np.inf), np.full(self.obs_size, np.inf)

    # ------------------------------------------------------------------ hooks
    def reset(self, rng: np.random.Generator) -> tuple[FloatArray, State]:
        """One swarm's start: poses (N, 3) and the state's arrays. Default: random poses on the floor, no state."""
        from swarmdeck.devices import random_initial_poses

        return random_initial_poses(self.n_agents, self.bounds, rng=rng), {}

    def observe(self, view: View) -> NDArray[np.floating[Any]]:
        """(E, N, D) observations. Default: own [x, y, cos θ, sin θ]."""
        p = view.poses
        return np.concatenate((p[..., :2], np.cos(p[..., 2:3]), np.sin(p[..., 2:3])), axis=-1)

    def reward(self, view: View) -> tuple[FloatArray, State]:
        """(E, N) rewards for the step just taken, and the new state. Default: zero, state unchanged."""
        return np.zeros(view.poses.shape[:2]), view.state

    def terminated(self, view: View) -> NDArray[np.bool_]:
        """(E,) swarms whose episode ended (success or failure). Default: none."""
        return np.zeros(view.poses.shape[0], dtype=bool)
