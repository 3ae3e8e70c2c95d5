"""Driving many robots to goal poses under the barrier, with a deadlock escape (setup and return).

The paper's back end moves the assigned robots to the experiment's start poses before a run and
back to the chargers after it (§III-A, §III-C), with no operator. :class:`Maneuver` gives, each
tick, the nominal single-integrator velocities ``(N, 2)`` of the robots' look-ahead points for
that; the caller passes them through :func:`~swarmdeck.devices.pipeline.certify` (the one
safety + actuation pipeline), so the barrier keeps every pair apart whatever the plan says.

Per robot, vectorised over robots:

* **pose control** — :class:`~swarmdeck.devices.controllers.HybridPoseController`: the
  look-ahead point is driven by the centre's position error (its equilibrium puts the centre on
  the goal), then the robot turns in place to the goal heading;
* **docking** (robots with ``reverse`` set, used by the return to the chargers) — once at the
  approach pose in front of a slot, the robot reverses straight onto the strip:
  v = −k·(distance along the dock line), ω = k_θ·wrap(θ_d + atan(k_y·e_lat) − θ), which steers a
  reversing unicycle back onto the dock line; a robot that arrives askew (off the line by more
  than ``dock_tolerance`` or turned) drives out to the approach pose and tries again, and so does
  one that gets a perturbed goal (below) while reversing;
* **progress** — the error e = ‖p − g‖ + 0.05 m·|θ − θ_g| to the current target; a robot that is not
  at its goal and has not lowered its best e by ``progress`` m within ``stall_time`` s is *stuck*
  (typically held by the barrier: a head-on meeting in a narrow gap, a ring of robots each
  blocked by the next, a goal enclosed by robots already parked);
* **deadlock escape** — robots have priorities (setup: deeper goals first, so the middle of
  the arena fills before its edges). A stuck robot keeps its goal and every lower-priority robot
  within ``yield_radius`` m that is not already escaping gets a *perturbed goal* for
  ``escape_time`` s: ``escape_offset`` m along the stuck robot's line to its target and a
  little off it, clipped inside the arena, so the higher-priority robot gains ground every
  round (head-on meetings in a gap and rings of robots come apart this way; a long corridor
  one robot wide can still jam: the yielding robot turns across the lane). A stuck robot with
  no lower-priority neighbour steps sideways (alternating sides every two attempts) and a
  little back. Robots reversing onto their charger slot keep to their lane and never yield.
  Offsets grow with each attempt (up to 2×; a robot at its goal starts over). A perturbed goal
  expires after its time and the robot resumes;
* **ordering** (return) — ``wait_for`` pairs keep a robot at its ``hold`` pose until another has
  docked (corner slots), and ``max_active`` lets only the highest-priority robots move at once.

Everything that runs each tick works on whole arrays (a k-d tree for neighbours), no per-robot
Python loop. Units: m, s, rad; poses ``(N, 3)``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.kinematics import GritsBotParams, unicycle_to_si, wrap_angle
from swarmdeck.core.obstacles import Obstacles
from swarmdeck.devices.controllers import HybridPoseController
from swarmdeck.devices.fleet.routing import RoutePlan, Router

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@dataclass(frozen=True)
class ManeuverParams:
    """Tolerances and gains of setup and return (defaults for GRITSBots on the 3.2 × 2 m arena).

    Attributes:
        position_tolerance: a robot is at its goal within this distance of the centre, m
            (the experiment's acceptance is 2 cm; the controller aims for 1.2 cm).
        heading_tolerance: … and within this heading error, rad (≈ 2.9°; acceptance 5°).
        speed_limit: look-ahead point speed while travelling, m/s.
        gain: look-ahead point velocity per m of the centre's position error, 1/s.
        arriving: robots within this distance of their target are finishing, never stuck, m.
        stall_time: a robot not at its goal whose error did not fall by ``progress`` within
            this many s is stuck, s.
        progress: m of progress that counts (position error + 0.05 m per rad of heading error).
        yield_radius: lower-priority robots within this distance of a stuck robot make way, m.
        escape_offset: length of a perturbed goal's displacement on the first attempt, m.
        escape_time: how long a perturbed goal is held, s.
        wall_clearance: perturbed goals keep this far from the walls, m.
        dock_speed: reversing speed onto the strip, m/s.
        dock_tolerance: a docked robot's centre is within this of its dock pose, m.
    """

    position_tolerance: float = 0.012
    heading_tolerance: float = 0.05
    speed_limit: float = 0.15
    gain: float = 2.0
    arriving: float = 0.03
    stall_time: float = 4.0
    progress: float = 0.01
    yield_radius: float = 0.45
    escape_offset: float = 0.3
    escape_time: float = 2.5
    wall_clearance: float = 0.15
    dock_speed: float = 0.08
    dock_tolerance: float = 0.01

    def __post_init__(self) -> None:
        from swarmdeck.core.checks import require_positive

        require_positive(self, ("position_tolerance", "heading_tolerance", "speed_limit", "gain", "arriving",
                                "stall_time", "progress",
                                "yield_radius", "escape_offset", "escape_time", "wall_clearance", "dock_speed",
                                "dock_tolerance"))


def goal_depth(goals: ArrayLike, bounds: Bounds) -> FloatArray:
    """``(N,)`` distance of each goal position from the nearest wall, m (deeper goals go first)."""
    g = np.asarray(goals, dtype=float)
    x0, x1, y0, y1 = bounds
    return np.min(np.column_stack((g[:, 0] - x0, x1 - g[:, 0], g[:, 1] - y0, y1 - g[:, 1])), axis=1)


class Maneuver:
    """Nominal commands that bring N robots to goal poses, with the deadlock escape (module docstring).

    Args:
        goals: ``(N, 3)`` goal poses (for docking robots: the dock pose).
        bounds: the arena, m.
        robot: the robot model (look-ahead ℓ).
        params: tolerances and gains.
        priority: ``(N,)`` higher goes first when robots block each other (default: deeper goals first).
        reverse: ``(N,)`` robots that dock: they first reach the approach pose ``approach`` then reverse.
        approach: ``(N, 3)`` approach poses (rows of robots without ``reverse`` are ignored).
        wait_for: ``(P, 2)`` pairs ``(i, j)``: robot i waits at its ``hold`` pose until robot j is at
            its goal (docking robots whose lanes cross at a corner dock one after the other).
        hold: ``(N, 3)`` where a waiting robot waits.
        max_active: at most this many robots move towards their goals at once, in priority order
            (the others stand still until one arrives); None: all.

    Call :meth:`nominal` once per tick with the current poses and time; read :attr:`escapes`
    (perturbed goals handed out) and :attr:`escaped` (robots that needed one) afterwards.
    """

    def __init__(self, goals: ArrayLike, bounds: Bounds = DEFAULT_BOUNDS, robot: GritsBotParams = GritsBotParams(),
                 params: ManeuverParams = ManeuverParams(), *, priority: ArrayLike | None = None,
                 reverse: ArrayLike | None = None, approach: ArrayLike | None = None,
                 wait_for: ArrayLike | None = None, hold: ArrayLike | None = None,
                 max_active: int | None = None) -> None:
        self.goals = np.array(goals, dtype=float)
        n = len(self.goals)
        if self.goals.shape != (n, 3) or not np.all(np.isfinite(self.goals)):
            raise ValueError(f"goals must be a finite (N, 3) array, got shape {self.goals.shape}")
        self.bounds, self.robot, self.params = bounds, robot, params
        if priority is None:
            depth = goal_depth(self.goals, bounds)
            priority = np.empty(n)
            priority[np.lexsort((np.arange(n), -depth))] = np.arange(n, 0, -1)
        self.priority = np.asarray(priority, dtype=float).reshape(n)
        self.reverse = np.zeros(n, dtype=bool) if reverse is None else np.asarray(reverse, dtype=bool).reshape(n)
        self.approach = self.goals.copy() if approach is None else np.array(approach, dtype=float).reshape(n, 3)
        self._docking = np.zeros(n, dtype=bool)  # reversing onto the strip
        pairs = np.empty((0, 2), dtype=np.intp) if wait_for is None else np.asarray(wait_for, dtype=np.intp).reshape(-1, 2)
        self._wait_i, self._wait_j = pairs[:, 0], pairs[:, 1]
        self.hold = self.approach.copy() if hold is None else np.array(hold, dtype=float).reshape(n, 3)
        self._waiting = np.zeros(n, dtype=bool)
        self.max_active = max_active
        self._rank = np.empty(n, dtype=np.intp)
        self._rank[np.lexsort((np.arange(n), -self.priority))] = np.arange(n)  # 0: highest priority
        self._hybrid = HybridPoseController(speed_limit=params.speed_limit,
                                            # hysteresis band [tol/3, tol]: a robot turning is within tol
                                            position_error=params.position_tolerance * 2 / 3,
                                            position_epsilon=params.position_tolerance / 3,
                                            rotation_error=params.heading_tolerance, lookahead=robot.lookahead,
                                            gain=params.gain)
        self._best = np.full(n, np.inf)
        self._best_t = np.zeros(n)
        self._esc_goal = np.zeros((n, 2))
        self._esc_until = np.full(n, -np.inf)
        self._attempts = np.zeros(n, dtype=np.int64)
        self.escapes = 0
        self.escaped = np.zeros(n, dtype=bool)
        self._router: Router | None = None
        self._plan: tuple[bytes, RoutePlan] | None = None
        self._route_len: FloatArray | None = None

    def route_around(self, obstacles: Obstacles | None) -> Maneuver:
        """Self, steering round the line-segment ``obstacles`` (None: none) by waypoints
        (:mod:`~swarmdeck.devices.fleet.routing`): a robot whose straight way to its target passes a segment
        aims at the next corner of the shortest way round instead, and its progress is measured along it."""
        self._router = None if obstacles is None or not obstacles.m else Router(obstacles, Bounds.of(self.bounds))
        self._plan = None
        return self

    def _routed(self, p: FloatArray, tgt: FloatArray) -> tuple[FloatArray, FloatArray] | None:
        """Waypoints ``(N, 2)`` and route lengths ``(N,)`` towards ``tgt``, or None without obstacles."""
        if self._router is None:
            return None
        key = tgt[:, :2].tobytes()
        if self._plan is None or self._plan[0] != key:  # the targets change with the phases only
            self._plan = (key, self._router.for_goals(tgt[:, :2]))
        return self._plan[1].waypoints(p[:, :2])

    @property
    def n(self) -> int:
        return len(self.goals)

    def targets(self) -> FloatArray:
        """``(N, 3)`` the pose each robot is heading for now, before perturbation (approach or goal)."""
        use_approach = self.reverse & ~self._docking
        out = np.where(use_approach[:, None], self.approach, self.goals)
        return np.where((self._waiting & ~self._docking)[:, None], self.hold, out)

    def at_goal(self, poses: ArrayLike, position: float | None = None, heading: float | None = None) -> BoolArray:
        """``(N,)`` robots within ``position`` m and ``heading`` rad of their final goal (defaults: the
        tolerances; docking robots must also be in the docking phase)."""
        p = np.asarray(poses, dtype=float)
        pos = self.params.position_tolerance if position is None else position
        head = self.params.heading_tolerance if heading is None else heading
        reach = np.where(self.reverse, self.params.dock_tolerance if position is None else position, pos)
        d = np.hypot(*(p[:, :2] - self.goals[:, :2]).T)
        ok = (d <= reach + 1e-9) & (np.abs(wrap_angle(p[:, 2] - self.goals[:, 2])) <= head + 1e-9)
        return ok & (~self.reverse | self._docking)

    def nominal(self, poses: ArrayLike, t: float) -> FloatArray:
        """``(N, 2)`` nominal look-ahead velocities, m/s, at time ``t`` s for the current ``poses``."""
        p = np.asarray(poses, dtype=float)
        prm, ell = self.params, self.robot.lookahead
        if len(self._wait_i):
            waiting = np.zeros(self.n, dtype=bool)
            np.logical_or.at(waiting, self._wait_i, ~self.at_goal(p)[self._wait_j])
            self._waiting = waiting
        # robots that reached their approach pose start reversing (and stay in that phase)
        tgt = self.targets()
        near_app = ((np.hypot(*(p[:, :2] - tgt[:, :2]).T) <= prm.position_tolerance)
                    & (np.abs(wrap_angle(p[:, 2] - tgt[:, 2])) <= prm.heading_tolerance))
        self._docking |= self.reverse & near_app
        # a robot that reversed onto its slot askew (pushed sideways on the way) drives out and tries again
        self._docking &= ~self._askew(p)
        escaping = t < self._esc_until
        self._docking &= ~escaping  # a docking robot asked to make way leaves its lane, then docks again
        self._docking &= ~self._waiting  # … and so does one that must let another dock first
        tgt = self.targets()
        aim = tgt.copy()
        aim[:, :2] = np.where(escaping[:, None], self._esc_goal, tgt[:, :2])
        routed = self._routed(p, tgt)
        self._route_len = None
        if routed is not None:  # round the obstacles: the next corner instead of the target
            free = ~escaping & ~self._docking
            aim[:, :2] = np.where(free[:, None], routed[0], aim[:, :2])
            self._route_len = np.where(free, routed[1], np.inf)
        v, w = self._hybrid(p, aim)
        u = unicycle_to_si(p, v, w, ell)
        if self._docking.any():
            u = np.where(self._docking[:, None], self._dock_velocity(p), u)
        active = self._active(p) | escaping
        self._watch(p, tgt, escaping, t, active)
        return np.where(active[:, None], u, 0.0)

    def _active(self, p: FloatArray) -> BoolArray:
        """``(N,)`` robots allowed to move: all, or the ``max_active`` highest-priority ones not yet at their
        goal (and every robot already at its goal, which holds it there)."""
        if self.max_active is None:
            return np.ones(self.n, dtype=bool)
        done = self.at_goal(p)
        pending_rank = np.cumsum(~done[np.argsort(self._rank)])[self._rank]  # 1-based among the pending
        return done | (pending_rank <= self.max_active)

    # ------------------------------------------------------------------ docking
    def _dock_frame(self, p: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Distance in front of the dock along its line and to the left of it, ``(N,)`` each, m."""
        g = self.goals
        c, s = np.cos(g[:, 2]), np.sin(g[:, 2])
        dx, dy = p[:, 0] - g[:, 0], p[:, 1] - g[:, 1]
        return c * dx + s * dy, -s * dx + c * dy

    def _askew(self, p: FloatArray) -> BoolArray:
        """``(N,)`` docking robots at the strip (within 2 cm) but off the dock line or heading."""
        along, lateral = self._dock_frame(p)
        head = np.abs(wrap_angle(p[:, 2] - self.goals[:, 2]))
        return (self._docking & (along < 0.02) & ((np.abs(lateral) > self.params.dock_tolerance)
                                                   | (head > 2 * self.params.heading_tolerance)))

    def _dock_velocity(self, p: FloatArray) -> FloatArray:
        """Reverse along each dock line (module docstring), as look-ahead velocities ``(N, 2)``."""
        g = self.goals
        along, lateral = self._dock_frame(p)  # along > 0: still in front of the dock
        v = -np.clip(2.0 * along, -self.params.dock_speed, self.params.dock_speed)
        theta_ref = g[:, 2] + np.arctan(8.0 * lateral) * (np.abs(along) > self.params.dock_tolerance)
        w = 3.0 * wrap_angle(theta_ref - p[:, 2])
        return unicycle_to_si(p, v, w, self.robot.lookahead)

    # ------------------------------------------------------------------ progress and escape
    def _watch(self, p: FloatArray, tgt: FloatArray, escaping: BoolArray, t: float, active: BoolArray) -> None:
        prm = self.params
        aim = np.where(escaping[:, None], self._esc_goal, tgt[:, :2])
        dist = np.hypot(*(p[:, :2] - aim).T)
        if self._route_len is not None:  # progress along the way round the obstacles
            dist = np.where(np.isfinite(self._route_len), self._route_len, dist)
        err = dist + 0.05 * np.abs(wrap_angle(p[:, 2] - tgt[:, 2])) * ~escaping
        done = self.at_goal(p) | (escaping & (np.hypot(*(p[:, :2] - aim).T) <= 2 * prm.position_tolerance))
        better = err < self._best - prm.progress
        reset = better | done | ~active  # robots told to stand still are not stuck
        self._best = np.where(reset, err, self._best)
        self._best_t = np.where(reset, t, self._best_t)
        self._attempts = np.where(self.at_goal(p), 0, self._attempts)
        arriving = np.hypot(*(p[:, :2] - aim).T) <= prm.arriving
        stuck = ~done & ~arriving & (t - self._best_t > prm.stall_time)
        if stuck.any():
            self._escape(p, tgt, stuck, escaping, t)

    def _escape(self, p: FloatArray, tgt: FloatArray, stuck: BoolArray, escaping: BoolArray, t: float) -> None:
        """Hand out perturbed goals to the robots that make way for each stuck robot (module docstring)."""
        from scipy.spatial import cKDTree

        prm, n = self.params, self.n
        pairs = cKDTree(p[:, :2]).query_pairs(prm.yield_radius, output_type="ndarray")
        both = np.concatenate((pairs, pairs[:, ::-1])) if len(pairs) else np.empty((0, 2), dtype=np.intp)
        i, j = both[:, 0], both[:, 1]
        # j makes way for stuck i when j ranks lower and is not escaping already
        # robots reversing onto (or sitting on) their charger slot keep to their lane: they never yield
        fixed = self.reverse & self._docking
        lower = stuck[i] & (self.priority[j] < self.priority[i]) & ~fixed[j]
        has_yielder = np.zeros(n, dtype=bool)
        has_yielder[i[lower]] = True  # waits while its lower-priority neighbours make way
        yield_pair = lower & ~escaping[j]
        i, j = i[yield_pair], j[yield_pair]
        # the first stuck robot (highest priority) a yielding robot makes way for decides its direction
        order = np.lexsort((-self.priority[i], j))
        first = np.ones(len(j), dtype=bool)
        first[1:] = j[order][1:] != j[order][:-1]
        i, j = i[order][first], j[order][first]
        alone = np.flatnonzero(stuck & ~has_yielder & ~escaping & ~fixed)
        movers = np.concatenate((j, alone))
        leader = np.concatenate((i, alone))
        if len(movers) == 0:
            return
        # the leader's line to its target; movers step off it sideways (even attempts) or away (odd)
        line = tgt[leader, :2] - p[leader, :2]
        line /= np.maximum(np.hypot(line[:, 0], line[:, 1]), 1e-9)[:, None]
        perp = np.column_stack((-line[:, 1], line[:, 0]))
        rel = p[movers, :2] - p[leader, :2]
        self_move = movers == leader
        side = np.where(self_move, np.where(self._attempts[movers] % 4 < 2, 1.0, -1.0),
                        np.sign(np.einsum("kd,kd->k", rel, perp) + 1e-12))
        dist = np.hypot(rel[:, 0], rel[:, 1])
        away = np.where(self_move[:, None], -line, rel / np.maximum(dist, 1e-9)[:, None])
        # yielding robots move ahead of the stuck robot along its line and a little off it (in a
        # corridor they back out the way they came, in a crowd the sideways part opens a gap);
        # a stuck robot nobody can yield to steps sideways and a little back
        direction = np.where(self_move[:, None], side[:, None] * perp + 0.3 * away, line + 0.2 * side[:, None] * perp)
        direction /= np.maximum(np.hypot(direction[:, 0], direction[:, 1]), 1e-9)[:, None]
        scale = prm.escape_offset * np.minimum(1.0 + 0.25 * self._attempts[movers], 2.0)
        goal = p[movers, :2] + scale[:, None] * direction
        goal = Bounds.of(self.bounds).clip(goal, prm.wall_clearance)
        self._esc_goal[movers] = goal
        self._esc_until[movers] = t + prm.escape_time
        self._attempts[movers] += 1
        self._best[movers] = np.inf
        self._best_t[movers] = t
        # the stuck robots that others make way for get a fresh window
        self._best_t[i] = t
        self._best[i] = np.inf
        self.escapes += int(len(movers))
        self.escaped[movers] = True
        self.escaped[i] = True
