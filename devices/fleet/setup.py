"""Setting robots up at an experiment's start poses (and driving them anywhere else), safely.

:func:`check_start_poses` refuses start poses the robots cannot take (outside the arena, closer
than the safety distance to each other or to a robot that stays docked) with the pose named.
:func:`drive` runs a :class:`~swarmdeck.devices.fleet.maneuver.Maneuver` on a simulated fleet's robot
ports as one :class:`~swarmdeck.devices.fleet.task.UpkeepTask` (the rules the console loop applies too):
each tick the task's nominal velocities for the moving robots pass through
:func:`~swarmdeck.devices.pipeline.certify` (the barrier; robots that do not move are fixed
obstacles and get zero commands), until every moving robot is at its goal or the time limit is
over. On failure the robots are stopped and :class:`SetupFailed` names the robots that did
not reach their pose.
"""
from __future__ import annotations

import time as _time
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.bounds import Bounds
from swarmdeck.core.constants import SAFETY_DISTANCE
from swarmdeck.core.errors import SwarmdeckError
from swarmdeck.core.kinematics import GritsBotParams, lookahead_points
from swarmdeck.core.ports import CommandSink, PoseSource, SensedPoses
from swarmdeck.devices.fleet.maneuver import Maneuver
from swarmdeck.devices.fleet.task import DONE, FLEET_WORDING, UpkeepTask
from swarmdeck.devices.pipeline import certify
from swarmdeck.devices.simulated_robots import SimulatedRobots
from swarmdeck.devices.simulator import SimulatedArena, check_poses

FloatArray = NDArray[np.float64]

#: the experiment's acceptance of a set-up robot: 2 cm and 5° from its start pose
ACCEPT_POSITION = 0.02
ACCEPT_HEADING = float(np.deg2rad(5.0))


@dataclass
class ManeuverReport:
    """How a setup (or return) went.

    Attributes:
        ok: every moving robot reached its goal within the time limit.
        sim_time: simulated s from start to finish (or to the time limit).
        wall_time: wall-clock s it took to compute.
        steps: control periods.
        max_position_error: largest distance of a moving robot from its goal at the end, m.
        max_heading_error: largest heading error at the end, rad.
        escapes: perturbed goals handed out by the deadlock escape.
        escaped: labels of the robots that needed one (or made way for one).
        collision_steps: steps with colliding robots (rps test) during the maneuver (0 expected).
        not_at_pose: labels of the robots that did not reach their goal (empty when ok).
    """

    ok: bool
    sim_time: float
    wall_time: float
    steps: int
    max_position_error: float
    max_heading_error: float
    escapes: int
    escaped: list[int] = field(default_factory=list)
    collision_steps: int = 0
    not_at_pose: list[int] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return {"ok": self.ok, "sim_time": self.sim_time, "wall_time": self.wall_time, "steps": self.steps,
                "max_position_error": self.max_position_error, "max_heading_error": self.max_heading_error,
                "max_heading_error_deg": float(np.rad2deg(self.max_heading_error)), "escapes": self.escapes,
                "escaped": list(self.escaped), "collision_steps": self.collision_steps,
                "not_at_pose": list(self.not_at_pose)}


class SetupFailed(RuntimeError, SwarmdeckError):
    """A setup or return did not finish in its time limit; the robots were stopped.

    Attributes:
        report: the :class:`ManeuverReport` (``not_at_pose`` names the robots).
    """

    def __init__(self, message: str, report: ManeuverReport) -> None:
        super().__init__(message)
        self.report = report


def start_separation(robot: GritsBotParams, safety_distance: float) -> float:
    """Least distance between the centres of two start poses, m: D_s + 2ℓ keeps the look-ahead
    points D_s apart whatever the headings (0.23 m for the GRITSBot and D_s = 0.17 m)."""
    return safety_distance + 2 * robot.lookahead


def check_start_poses(poses: ArrayLike, bounds: Bounds, robot: GritsBotParams = GritsBotParams(), *,
                      safety_distance: float = SAFETY_DISTANCE, wall_margin: float | None = None,
                      obstacles: ArrayLike | None = None, obstacle_names: list[str] | None = None) -> FloatArray:
    """Validated copy of ``(N, 3)`` start poses; ValueError naming the first bad pose.

    A pose is bad when its robot would not fit inside the arena (centre closer than the body
    radius to a wall, or look-ahead point closer than ``wall_margin``, default D_s/2, the barrier's
    wall margin), when two poses' centres are closer than :func:`start_separation`, or when a
    pose's look-ahead point would be within ``safety_distance`` + ℓ of an ``obstacles`` point
    ``(M, 2)`` (robots that stay docked; ``obstacle_names`` says which in the message).
    """
    p = check_poses(poses, "start poses")
    x0, x1, y0, y1 = bounds
    r, ell = robot.radius, robot.lookahead
    margin = safety_distance / 2 if wall_margin is None else wall_margin
    pts = lookahead_points(p, ell)
    out = ((p[:, 0] - r < x0) | (p[:, 0] + r > x1) | (p[:, 1] - r < y0) | (p[:, 1] + r > y1)
           | (pts[:, 0] < x0 + margin) | (pts[:, 0] > x1 - margin) | (pts[:, 1] < y0 + margin) | (pts[:, 1] > y1 - margin))
    if out.any():
        k = int(np.flatnonzero(out)[0])
        raise ValueError(f"start pose {k} ({p[k, 0]:.3f}, {p[k, 1]:.3f}, {p[k, 2]:.3f}) is outside the arena "
                         f"{tuple(bounds)}: the robot must stay {r} m (body) and its look-ahead point {margin} m "
                         "inside the walls")
    from scipy.spatial import cKDTree

    sep = start_separation(robot, safety_distance)
    pairs = cKDTree(p[:, :2]).query_pairs(sep - 1e-9, output_type="ndarray")
    if len(pairs):
        i, j = (int(v) for v in pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))][0])
        gap = float(np.hypot(*(p[i, :2] - p[j, :2])))
        raise ValueError(f"start poses {i} and {j} are {gap:.3f} m apart, closer than the safety distance {sep:.3f} m "
                         f"between robot centres (D_s {safety_distance} m + 2 x look-ahead {ell} m)")
    if obstacles is not None and len(np.asarray(obstacles)):
        obs = np.asarray(obstacles, dtype=float).reshape(-1, 2)
        need = safety_distance + ell
        d, k = cKDTree(obs).query(p[:, :2])
        bad = d < need
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            who = obstacle_names[int(k[i])] if obstacle_names is not None else f"obstacle {int(k[i])}"
            raise ValueError(f"start pose {i} ({p[i, 0]:.3f}, {p[i, 1]:.3f}) is {d[i]:.3f} m from {who}, closer than "
                             f"{need:.3f} m (D_s + look-ahead): choose poses farther from the chargers")
    return p


class UpkeepRobots(PoseSource, CommandSink, Protocol):
    """Robot ports a fleet maneuver can be driven over (:func:`drive`): on a simulated clock
    (``read(now).time``), with the robot model (``params``) and the simulator's validation counts
    (``report.steps_with_collision``) — ``FleetManager``, :class:`SimulatedRobots`."""

    def read(self, now: float = 0.0) -> SensedPoses:
        """The robots' poses on their own simulated clock (``now``, s, is not needed)."""

    @property
    def params(self) -> GritsBotParams: ...

    @property
    def report(self) -> Any: ...


def drive(robots: UpkeepRobots | SimulatedArena, maneuver: Maneuver, rows: ArrayLike, filt: Any, *,
          time_limit: float, labels: ArrayLike | None = None, accept_position: float = ACCEPT_POSITION,
          accept_heading: float = ACCEPT_HEADING, what: str = "setup", lost_after: float | None = 1.0
          ) -> ManeuverReport:
    """Drive rows ``rows`` (``(K,)``, the maneuver's robots in order) of the robots' readings until every
    one is at its goal (the maneuver's tolerances) or ``time_limit`` s of the robots' simulated clock have
    passed: one :class:`~swarmdeck.devices.fleet.task.UpkeepTask` (the rules, as the console loop's
    ``FleetManeuver`` applies them) stepped over the robot ports ``robots`` (``FleetManager``,
    :class:`SimulatedRobots`; a bare :class:`SimulatedArena` is wrapped, without batteries).

    The other robots stand still and are fixed obstacles of the barrier ``filt``
    (``certify(..., seen=moving)``). ``labels`` ``(K,)`` name the robots in messages (default: the rows).
    A moving robot not seen for ``lost_after`` s stops the maneuver (None: never).

    Raises:
        SetupFailed: the time limit passed (or a robot was lost); every robot was stopped first. Its
            report names the robots (by label) farther than ``accept_position`` m / ``accept_heading``
            rad from their goal.
    """
    ports: UpkeepRobots = SimulatedRobots(sim=robots) if isinstance(robots, SimulatedArena) else robots
    rows = np.asarray(rows, dtype=np.intp).reshape(-1)
    labels_arr = rows if labels is None else np.asarray(labels).reshape(-1)
    task = UpkeepTask(what, labels_arr, maneuver, time_limit=time_limit, lost_after=lost_after, wording=FLEET_WORDING)
    first = ports.read()
    if first.time is None:
        raise ValueError(f"{what}: drive needs robots on a simulated clock (the reading has no time); "
                         "real robots are driven by the console loop (FleetManeuver)")
    m = len(first.ids)
    moving = np.zeros(m, dtype=bool)
    moving[rows] = True
    robot = ports.params
    t0, wall0 = float(first.time), _time.perf_counter()
    collisions0 = ports.report.steps_with_collision
    steps = 0
    u = np.zeros((m, 2))
    while True:
        reading = ports.read()
        nominal = task.update(float(reading.time), reading.poses[rows], seen=reading.seen[rows])
        if nominal is None:
            break
        u[rows] = nominal
        cert = certify(reading.poses, u, robot, filt, seen=moving)
        ports.send(reading.ids, cert.v, cert.w)
        steps += 1
    ok = task.state == DONE
    if not ok:  # stop: the robots hold still (the firmware would brake anyway)
        ports.send(reading.ids, np.zeros(m), np.zeros(m))
        reading = ports.read()
    final = reading.poses[rows]
    pos_err, head_err = task.errors(final)
    if ok:
        off = (pos_err > accept_position) | (head_err > accept_heading)
    elif task.timed_out:
        task.stopped_at(final)  # a time-out: named over the poses the robots stopped at
        off = task.not_at_pose
    else:
        off = ~maneuver.at_goal(final)
    report = ManeuverReport(ok, float(reading.time) - t0, _time.perf_counter() - wall0, steps,
                            float(pos_err.max()), float(head_err.max()), maneuver.escapes,
                            [int(v) for v in labels_arr[maneuver.escaped]],
                            int(ports.report.steps_with_collision - collisions0),
                            [int(v) for v in labels_arr[off]])
    if not ok:
        raise SetupFailed(task.message, report)
    return report
