"""One fleet-upkeep task: the rules of a setup or a return, whoever drives it.

An :class:`UpkeepTask` is a :class:`~swarmdeck.devices.fleet.maneuver.Maneuver` (goals, pose
control, deadlock escape) with the robots that move (``ids``, in the maneuver's row order), a time
limit, the lost-robot rule, progress and the failure messages (REFERENCE.md §11, paper §III-A/C).
Each control period the driver hands it the moving robots' poses; it answers with their nominal
look-ahead velocities ``(K, 2)`` m/s — which the driver passes through
:func:`~swarmdeck.devices.pipeline.certify`, the one safety pipeline — or ends (done or failed, with
the message that names the robots). Two drivers use it:

* :func:`swarmdeck.devices.fleet.setup.drive` — a loop over robot ports (``FleetManager.read/send``,
  a simulation's ports): ``FleetManager.setup/return_to_chargers`` and the experiment runner;
* :class:`swarmdeck.console.runtime.fleet_upkeep.FleetManeuver` — a console-loop behaviour over
  the task (``swarmdeck console``/``swarmdeck fleet``/the portal's arena).

The two paths word a time-out apart (kept as they were: :class:`UpkeepWording`): the fleet's
reports "robot 3 4.2 cm / 7.1 deg away; every robot was stopped" over the poses after the stop, the
console's "robot 3 4.2 cm away; every robot stopped" over the last tick's poses.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.kinematics import wrap_angle
from swarmdeck.devices.fleet.maneuver import Maneuver

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

RUNNING, DONE, FAILED = "running", "done", "failed"


@dataclass(frozen=True)
class UpkeepWording:
    """How a task words its time-out and when its time is up (one per driver, kept as they were).

    Attributes:
        heading: name each robot's heading error too ("4.2 cm / 7.1 deg away").
        stopped: the message's ending ("every robot was stopped").
        limit_reached: the time is up at ``t >= limit`` (−1 ns), else only once ``t > limit``.
    """

    heading: bool
    stopped: str
    limit_reached: bool


#: the fleet's own driver (:func:`~swarmdeck.devices.fleet.setup.drive`)
FLEET_WORDING = UpkeepWording(heading=True, stopped="every robot was stopped", limit_reached=True)
#: the console loop's behaviour (``FleetManeuver``)
LOOP_WORDING = UpkeepWording(heading=False, stopped="every robot stopped", limit_reached=False)


class UpkeepTask:
    """Robots ``ids`` driven to the goals of ``maneuver`` within ``time_limit`` s (module docstring).

    Args:
        name: what it is, in every message (``"setup"``, ``"set up"``, ``"return to chargers"``…).
        ids: ``(K,)`` robot ids (labels) of the moving robots, in the maneuver's row order.
        maneuver: goals, controller and deadlock escape.
        time_limit: s of the driver's clock from the first :meth:`update`.
        lost_after: a moving robot without a fresh pose for this many s (or gone from the
            reading) fails the task; None: never (robots that are always seen).
        wording: how the time-out is worded (:data:`FLEET_WORDING`, :data:`LOOP_WORDING`).

    Attributes:
        state: ``"running"``, ``"done"`` or ``"failed"`` (nothing to do: done at once).
        message: the progress line while running, the outcome once over.
        elapsed: s since the first update. at_goal: ``(K,)`` at the last update.
        final_errors: (m, rad) the largest position and heading errors when done, else None.
        timed_out: it failed on its time limit (not a lost robot).
        not_at_pose: ``(K,)`` robots not at their goal when it failed on time.
    """

    def __init__(self, name: str, ids: ArrayLike, maneuver: Maneuver, *, time_limit: float,
                 lost_after: float | None = None, wording: UpkeepWording = LOOP_WORDING) -> None:
        self.name = name
        self.ids = np.asarray(ids, dtype=np.int64).reshape(-1)
        if len(self.ids) != maneuver.n:
            raise ValueError(f"{name}: {len(self.ids)} robot ids for a maneuver of {maneuver.n} robots")
        self.maneuver = maneuver
        self.time_limit = float(time_limit)
        self.lost_after = lost_after
        self.wording = wording
        k = len(self.ids)
        self.state = RUNNING if k else DONE
        self.message = f"{name}: starting" if k else f"{name}: nothing to do"
        self.elapsed = 0.0
        self.at_goal = np.zeros(k, dtype=bool)
        self.final_errors: tuple[float, float] | None = None
        self.not_at_pose = np.zeros(k, dtype=bool)
        self.timed_out = False
        self._t0: float | None = None
        self._last_seen = np.full(k, np.nan)

    def update(self, now: float, poses: ArrayLike, present: ArrayLike | None = None,
               seen: ArrayLike | None = None) -> FloatArray | None:
        """One control period at ``now`` s (the driver's clock) with the moving robots' ``poses`` ``(K, 3)``.

        ``present`` ``(K,)``: robots in the reading (default all; rows of absent ones are ignored),
        ``seen`` ``(K,)``: robots with a fresh pose (default all).

        Returns:
            ``(K, 2)`` nominal look-ahead velocities, m/s, while running; None once the task is over
            (:attr:`state` done or failed, :attr:`message` says how).
        """
        if self.state != RUNNING:
            return None
        k = len(self.ids)
        if self._t0 is None:
            self._t0 = now
            self._last_seen[:] = now
        t = now - self._t0
        self.elapsed = t
        here = np.ones(k, dtype=bool) if present is None else np.asarray(present, dtype=bool).reshape(k)
        fresh = here if seen is None else here & np.asarray(seen, dtype=bool).reshape(k)
        self._last_seen = np.where(fresh, now, self._last_seen)
        if self.lost_after is not None:
            lost = ~here | (now - self._last_seen > self.lost_after)
            if lost.any():
                gone = ", ".join(f"robot {int(i)}" + ("" if p else " (gone from the robots' reports)")
                                 for i, p in zip(self.ids[lost], here[lost]))
                self._end(FAILED, f"{self.name} stopped: {gone} stopped reporting its pose for more than "
                                  f"{self.lost_after:g} s; every robot stopped")
                return None
        p = np.asarray(poses, dtype=float)
        self.at_goal = self.maneuver.at_goal(p)
        if self.at_goal.all():
            err, head = self.errors(p)
            self.final_errors = (float(err.max()), float(head.max()))
            escaped = int(self.maneuver.escaped.sum())
            self._end(DONE, f"{self.name}: done in {t:.1f} s, {k} robot(s) at their poses (largest error "
                            f"{100 * self.final_errors[0]:.1f} cm, {math.degrees(self.final_errors[1]):.1f}°)"
                            + (f"; deadlock escape used by {escaped}" if escaped else ""))
            return None
        up = t >= self.time_limit - 1e-9 if self.wording.limit_reached else t > self.time_limit
        if up:
            self.state, self.timed_out = FAILED, True
            self.stopped_at(p)
            return None
        u = self.maneuver.nominal(p, t)
        self.message = (f"{self.name}: {int(self.at_goal.sum())}/{k} robots at their poses, "
                        f"{t:.1f} s" + (f", {self.maneuver.escapes} escape(s)" if self.maneuver.escapes else ""))
        return u

    def errors(self, poses: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """``(K,)`` distances, m, and ``(K,)`` absolute heading errors, rad, of ``poses`` from the goals."""
        p, g = np.asarray(poses, dtype=float), self.maneuver.goals
        return np.hypot(*(p[:, :2] - g[:, :2]).T), np.abs(wrap_angle(p[:, 2] - g[:, 2]))

    def stopped_at(self, poses: ArrayLike) -> str:
        """After a time-out: the robots stopped at ``poses`` ``(K, 3)``; the message names those not at
        their goal (:attr:`not_at_pose`) and how far away they are. Returns the message."""
        p = np.asarray(poses, dtype=float)
        off = ~self.maneuver.at_goal(p)
        err, head = self.errors(p)
        if self.wording.heading:
            detail = ", ".join(f"robot {int(i)} {e * 100:.1f} cm / {np.rad2deg(a):.1f} deg away"
                               for i, e, a in zip(self.ids[off], err[off], head[off]))
        else:
            detail = ", ".join(f"robot {int(i)} {100 * e:.1f} cm away" for i, e in zip(self.ids[off], err[off]))
        self.not_at_pose = off
        self.message = f"{self.name} did not finish within {self.time_limit:g} s: {detail}; {self.wording.stopped}"
        return self.message

    def _end(self, state: str, message: str) -> None:
        self.state, self.message = state, message


__all__ = ["DONE", "FAILED", "FLEET_WORDING", "LOOP_WORDING", "RUNNING", "UpkeepTask", "UpkeepWording"]
