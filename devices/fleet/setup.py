"""Setting robots up at an experiment's start poses (and driving them anywhere else), safely.

:func:`check_start_poses` refuses start poses the robots cannot take (outside the arena, closer
than the safety distance to each other or to a robot that stays docked) with the pose named.
:func:`drive` runs a :class:`~swarmdeck.devices.fleet.maneuver.Maneuver` on a simulated fleet:
each tick the maneuver's nominal velocities for the moving robots pass through
:func:`~swarmdeck.devices.pipeline.certify` (the barrier; robots that do not move are fixed
obstacles and get zero commands), until every moving robot is at its goal or the time limit is
over. On failure the robots are stopped and :class:`SetupFailed` names the robots that did
not reach their pose.
"""
from __future__ import annotations

import time as _time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.bounds import Bounds
from swarmdeck.core.errors import SwarmdeckError
from swarmdeck.core.kinematics import GritsBotParams, lookahead_points
from swarmdeck.devices.fleet.maneuver import Maneuver
from swarmdeck.devices.gritsbot import wrap_angle
from swarmdeck.devices.pipeline import certify
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
                      safety_distance: float = 0.17, wall_margin: float | None = None,
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


def drive(sim: SimulatedArena, maneuver: Maneuver, rows: ArrayLike, filt: Any, *, time_limit: float,
          labels: ArrayLike | None = None, accept_position: float = ACCEPT_POSITION,
          accept_heading: float = ACCEPT_HEADING, what: str = "setup", on_step: Any = None) -> ManeuverReport:
    """Drive fleet rows ``rows`` (``(K,)``, the maneuver's robots in order) of ``sim`` until every one is
    at its goal (the maneuver's tolerances) or ``time_limit`` simulated s have passed.

    The other robots of ``sim`` stand still and are fixed obstacles of the barrier ``filt``
    (``certify(..., seen=moving)``). ``on_step(sim, v, w)`` is called after each step (battery).
    ``labels`` ``(K,)`` name the robots in messages (default: the rows).

    Raises:
        SetupFailed: the time limit passed; every robot was stopped first. Its report names the
            robots (by label) farther than ``accept_position`` m / ``accept_heading`` rad from their goal.
    """
    rows = np.asarray(rows, dtype=np.intp).reshape(-1)
    labels_arr = rows if labels is None else np.asarray(labels).reshape(-1)
    m = sim.n_robots
    moving = np.zeros(m, dtype=bool)
    moving[rows] = True
    robot = sim.params
    t0, wall0 = sim.time, _time.perf_counter()
    collisions0 = sim.report.steps_with_collision
    steps = 0
    u = np.zeros((m, 2))
    while True:
        poses = sim.poses
        t = sim.time - t0
        if maneuver.at_goal(poses[rows]).all():
            ok = True
            break
        if t >= time_limit - 1e-9:
            ok = False
            break
        u[rows] = maneuver.nominal(poses[rows], t)
        cert = certify(poses, u, robot, filt, seen=moving)
        sim.step(cert.v, cert.w)
        if on_step is not None:
            on_step(sim, cert.v, cert.w)
        steps += 1
    if not ok:
        sim.step(np.zeros(m), np.zeros(m))  # stop: the robots hold still (the firmware would brake anyway)
        if on_step is not None:
            on_step(sim, np.zeros(m), np.zeros(m))
    final = sim.poses[rows]
    goals = maneuver.goals
    pos_err = np.hypot(*(final[:, :2] - goals[:, :2]).T)
    head_err = np.abs(wrap_angle(final[:, 2] - goals[:, 2]))
    off = (pos_err > accept_position) | (head_err > accept_heading) if ok else ~maneuver.at_goal(final)
    report = ManeuverReport(ok, float(sim.time - t0), _time.perf_counter() - wall0, steps, float(pos_err.max()),
                            float(head_err.max()), maneuver.escapes,
                            [int(v) for v in labels_arr[maneuver.escaped]],
                            int(sim.report.steps_with_collision - collisions0),
                            [int(v) for v in labels_arr[off]])
    if not ok:
        detail = ", ".join(f"robot {int(labels_arr[k])} {pos_err[k] * 100:.1f} cm / {np.rad2deg(head_err[k]):.1f} deg away"
                           for k in np.flatnonzero(off))
        raise SetupFailed(f"{what} did not finish within {time_limit:g} s: {detail}; every robot was stopped", report)
    return report
