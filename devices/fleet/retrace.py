"""Returning to the chargers by retracing a planned setup backwards (a full arena docks every robot).

Driving 50 robots at once from wherever an experiment left them onto all 50 charger slots jams:
the lanes in front of the strips, the corners and the approach poses crowd. The reverse problem
does not: a setup from every slot to any start poses finishes (deeper goals first, the deadlock
escape). A unicycle's motion played backwards — the same poses in reverse order under the
commands ``(−v, −ω)`` — is again a motion of the unicycle, and every pair of robots is exactly as
far apart at each instant as in the forward run, so a collision-free setup reversed is a
collision-free return that ends on the slots. Hence:

1. :func:`plan_retrace` simulates that setup (the fleet's barrier with a few mm more safety
   distance, the robots that stay docked as fixed obstacles) from the slots the robots will take
   (:func:`~swarmdeck.devices.fleet.docking.choose_slots`) to the robots' present poses and
   records poses ``(S + 1, K, 3)`` and applied commands ``(S, K, 2)``. The margin matters: the
   barrier is not symmetric in time (robots may part fast but close in only slowly near the safety
   distance), so a plan that grazes the safety distance cannot be tracked backwards under the same
   barrier; planned a little wider apart, it never touches it;
2. :class:`RetraceManeuver` plays it backwards: a unicycle tracking controller (Kanayama et al.
   1990, with the heading gain on |v_r| so it is stable backing up too: v = v_r cos e_θ + k_x e_x,
   ω = ω_r + v_r k_y e_y + (k_θ |v_r| + k_0) sin e_θ, errors in the robot frame) follows the
   reversed poses; each robot's reference clock slows and stops while it lags (``lag_start`` …
   ``lag_stop`` m behind) and never runs more than ``window`` s ahead of the slowest, so the robots
   keep the plan's timing relative to each other; after the plan's end (or when every clock has
   stood still for ``give_up`` s) the :class:`~swarmdeck.devices.fleet.maneuver.Maneuver` docking
   logic finishes (a robot off its dock line drives out to its approach pose and backs in again).

Every command still goes through the caller's barrier, so a lagging or disturbed robot is held
back, never run into another. Units: m, s, rad.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.constants import CONTROL_PERIOD, SAFETY_DISTANCE
from swarmdeck.core.kinematics import GritsBotParams, lookahead_points, unicycle_to_si, wrap_angle
from swarmdeck.devices.chargers import ChargerLayout
from swarmdeck.devices.fleet.maneuver import Maneuver, ManeuverParams
from swarmdeck.devices.fleet.setup import drive
from swarmdeck.devices.pipeline import barrier_filter
from swarmdeck.devices.simulated_robots import SimulatedRobots
from swarmdeck.devices.simulator import ArenaConfig, SimulatedArena

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


@dataclass(frozen=True)
class RetraceGains:
    """Tracking the reversed plan (defaults for GRITSBots at ≤ 0.2 m/s).

    Attributes:
        k_x: along-track gain, 1/s.
        k_y: cross-track gain, 1/m² (times v_r).
        k_theta: heading gain per m/s of |v_r|, 1/m.
        k_0: heading gain while the reference turns in place, 1/s.
        lag_start: the reference clock slows once a robot is this far from its reference, m …
        lag_stop: … and stops at this distance, m (heading errors count ``heading_weight`` m per rad).
        window: no robot's reference runs more than this ahead of the slowest one's, s.
        give_up: after every robot's clock has stood still this many s, the docking logic takes over, s.
    """

    k_x: float = 3.0
    k_y: float = 200.0
    k_theta: float = 5.0
    k_0: float = 2.0
    lag_start: float = 0.01
    lag_stop: float = 0.03
    heading_weight: float = 0.1
    give_up: float = 3.0
    window: float = 1.0

    def __post_init__(self) -> None:
        from swarmdeck.core.checks import require_positive

        require_positive(self, ("k_x", "k_y", "k_theta", "k_0", "lag_start", "lag_stop", "heading_weight", "give_up",
                                "window"))
        if self.lag_stop <= self.lag_start:
            raise ValueError(f"RetraceGains: lag_stop ({self.lag_stop}) must exceed lag_start ({self.lag_start})")


@dataclass(frozen=True)
class RetracePlan:
    """A recorded setup from the slots to the present poses (to be played backwards).

    Attributes:
        poses: ``(S + 1, K, 3)`` poses of the K returning robots at each planning tick (row 0: docked).
        commands: ``(S, K, 2)`` the ``(v, ω)`` applied between tick s and s + 1.
        dt: planning period, s.
    """

    poses: FloatArray
    commands: FloatArray
    dt: float

    @property
    def steps(self) -> int:
        return int(len(self.commands))


def phantom_slots(poses: ArrayLike, slots: ArrayLike, layout: ChargerLayout, robot: GritsBotParams,
                  safety_distance: float) -> IntArray:
    """Slots other than ``slots`` assumed occupied when the caller does not say: every one whose docked
    robot's look-ahead point would be at least ``safety_distance`` m from each returning robot's (at
    ``poses`` ``(K, 3)``) — robots that stay docked are then never forgotten, and no phantom stands
    where a returning robot is."""
    rest = np.setdiff1d(np.arange(layout.n_slots), np.asarray(slots, dtype=np.intp))
    if len(rest) == 0:
        return rest
    docked = lookahead_points(layout.dock_poses()[rest], robot.lookahead)
    here = lookahead_points(np.asarray(poses, dtype=float).reshape(-1, 3), robot.lookahead)
    d = np.hypot(*(docked[:, None, :] - here[None, :, :]).transpose(2, 0, 1))
    return rest[np.all(d >= safety_distance, axis=1)]


def plan_retrace(poses: ArrayLike, slots: ArrayLike, layout: ChargerLayout, robot: GritsBotParams = GritsBotParams(),
                 params: ManeuverParams = ManeuverParams(), *, occupied: ArrayLike | None = None,
                 safety_distance: float = SAFETY_DISTANCE, gamma: float = 20.0, dt: float = CONTROL_PERIOD,
                 margin: float = 0.008, time_limit: float | None = None) -> RetracePlan:
    """Simulate the setup from ``slots`` ``(K,)`` to ``poses`` ``(K, 3)`` (module docstring) and record it.

    ``occupied``: slots whose robots stay docked (fixed obstacles of the plan); default
    :func:`phantom_slots`. The barrier is the fleet's (linear κ, ``gamma``) with ``safety_distance`` +
    ``margin`` (the docked robots' look-ahead points are 0.18 m apart on the default layout).

    Raises:
        SetupFailed: the setup did not reach every pose within ``time_limit`` s (default 60 + 2 K).
    """
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    slots = np.asarray(slots, dtype=np.intp).reshape(-1)
    k = len(p)
    if occupied is None:
        occupied = phantom_slots(p, slots, layout, robot, safety_distance)
    occupied = np.setdiff1d(np.asarray(occupied, dtype=np.intp).reshape(-1), slots)
    docks = layout.dock_poses()
    sim = SimulatedArena(initial_poses=np.vstack((docks[slots], docks[occupied])),
                         config=ArenaConfig(bounds=layout.bounds, dt=dt), params=robot)
    # planned ``margin`` m wider apart than the barrier that runs it: played backwards with small tracking
    # errors, no pair comes near the barrier's boundary, so it never has to bend the reversed paths
    filt = barrier_filter(robot, layout.bounds, dt, class_k="linear", gamma=gamma,
                          safety_distance=safety_distance + margin)
    robots = _RecordingRobots(sim, k)
    limit = 60.0 + 2.0 * k if time_limit is None else float(time_limit)
    drive(robots, Maneuver(p, layout.bounds, robot, params), np.arange(k), filt, time_limit=limit,
          what="planning the return")
    trace, applied = robots.trace, robots.commands
    return RetracePlan(np.array(trace), np.array(applied).reshape(-1, k, 2), dt)


class _RecordingRobots(SimulatedRobots):
    """The planning simulation's ports, recording the first ``k`` robots' poses ``(3,)`` after every
    period and the ``(v, ω)`` applied to them."""

    def __init__(self, sim: SimulatedArena, k: int) -> None:
        super().__init__(sim=sim)
        self._k = k
        self.trace: list[FloatArray] = [sim.poses[:k]]
        self.commands: list[FloatArray] = []

    def send(self, ids: NDArray[np.int64], v: NDArray[np.float64], w: NDArray[np.float64]) -> None:
        super().send(ids, v, w)
        self.trace.append(self.sim.poses[:self._k])
        av, aw = self.sim.applied
        self.commands.append(np.column_stack((av[:self._k], aw[:self._k])))


class RetraceManeuver(Maneuver):
    """Plays a :class:`RetracePlan` backwards, then docks with :class:`Maneuver`'s logic (module docstring).

    Args:
        plan: the recorded setup.
        slots: ``(K,)`` the slot of each robot (the plan starts on them).
        layout, robot, params: as for :class:`Maneuver` (approach poses and docking tolerances).
        gains: the tracking controller.
        wait_for, hold, priority: passed on to :class:`Maneuver` (used after the plan's end).

    ``at_goal`` is True for a robot docked within the tolerances; :attr:`replaying` says whether
    the reversed plan is still running.
    """

    def __init__(self, plan: RetracePlan, slots: ArrayLike, layout: ChargerLayout,
                 robot: GritsBotParams = GritsBotParams(), params: ManeuverParams = ManeuverParams(),
                 gains: RetraceGains = RetraceGains(), **kwargs) -> None:
        slots = np.asarray(slots, dtype=np.intp).reshape(-1)
        k = len(slots)
        if plan.poses.shape[1:] != (k, 3):
            raise ValueError(f"the plan is for {plan.poses.shape[1]} robots, not {k}")
        super().__init__(layout.dock_poses()[slots], layout.bounds, robot, params, reverse=np.ones(k, dtype=bool),
                         approach=layout.approach_poses()[slots], **kwargs)
        self._docking[:] = True  # the plan ends on the docks: at_goal counts from the start
        self.plan, self.gains = plan, gains
        self._ref = plan.poses[::-1].copy()  # reversed: row 0 is where the robots are now
        self._ref[:, :, 2] = np.unwrap(self._ref[:, :, 2], axis=0)
        self._uref = -plan.commands[::-1]  # command from reversed row s to s + 1
        self._s = np.zeros(k)  # each robot's position on the reversed plan, in ticks
        self._t_last: float | None = None
        self._paused_since: float | None = None
        self._handed_over = plan.steps == 0

    def _hand_over(self, p: FloatArray) -> None:
        """The docking logic takes over: robots in their slot's lane (on its line, between the dock and
        a little past the approach pose, facing into the arena) back in; the others first drive to their
        approach pose."""
        along, lateral = self._dock_frame(p)
        reach = np.hypot(*(self.approach[:, :2] - self.goals[:, :2]).T) + 0.05
        facing = np.abs(wrap_angle(p[:, 2] - self.goals[:, 2])) <= 0.3
        self._docking = (np.abs(lateral) <= 0.02) & (along >= -0.02) & (along <= reach) & facing
        self._handed_over = True

    @property
    def replaying(self) -> bool:
        return not self._handed_over

    def reference(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Reference poses ``(K, 3)`` and commands ``v_r``, ``ω_r`` ``(K,)`` at each robot's plan position."""
        s_max = self.plan.steps
        s = np.minimum(self._s, float(s_max))
        i = np.minimum(np.floor(s).astype(np.intp), s_max - 1)
        f = (s - i)[:, None]
        k = np.arange(self.n)
        pose = (1.0 - f) * self._ref[i, k] + f * self._ref[i + 1, k]
        u = np.where((s < s_max)[:, None], self._uref[i, k], 0.0)
        return pose, u[:, 0], u[:, 1]

    def nominal(self, poses: ArrayLike, t: float) -> FloatArray:
        p = np.asarray(poses, dtype=float)
        if self._handed_over:
            return super().nominal(p, t)
        g = self.gains
        dt_call = 0.0 if self._t_last is None else max(0.0, t - self._t_last)
        self._t_last = t
        ref, vr, wr = self.reference()
        lag = np.hypot(*(ref[:, :2] - p[:, :2]).T) + g.heading_weight * np.abs(wrap_angle(ref[:, 2] - p[:, 2]))
        rate = np.clip((g.lag_stop - lag) / (g.lag_stop - g.lag_start), 0.0, 1.0)
        # each robot's clock runs while it keeps up, at most ``window`` s ahead of the slowest
        ahead = self._s - self._s.min() >= g.window / self.plan.dt
        rate = np.where(ahead, 0.0, rate)
        s_max = float(self.plan.steps)
        self._s = np.minimum(self._s + rate * min(dt_call, 2 * self.plan.dt) / self.plan.dt, s_max)
        moving = (rate > 0.0) & (self._s < s_max)
        if moving.any() or self._paused_since is None:
            self._paused_since = None if moving.any() else t
        if np.all(self._s >= s_max) or (self._paused_since is not None and t - self._paused_since > g.give_up):
            self._hand_over(p)
            return super().nominal(p, t)
        ref, vr, wr = self.reference()
        c, s = np.cos(p[:, 2]), np.sin(p[:, 2])
        dx, dy = ref[:, 0] - p[:, 0], ref[:, 1] - p[:, 1]
        ex, ey = c * dx + s * dy, -s * dx + c * dy
        eth = wrap_angle(ref[:, 2] - p[:, 2])
        vr, wr = rate * vr, rate * wr  # a paused reference stands still
        v = vr * np.cos(eth) + g.k_x * ex
        w = wr + vr * g.k_y * ey + (g.k_theta * np.abs(vr) + g.k_0) * np.sin(eth)
        return unicycle_to_si(p, v, w, self.robot.lookahead)

