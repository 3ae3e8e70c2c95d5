"""Fleet upkeep through the console's loop: set robots up at start poses, return them to the chargers.

The paper's back end prepares the arena between experiments (§III-A, §III-C): charged robots are
assigned and driven to the experiment's start poses; afterwards they go back to the charging
strips. Here both run as a console behaviour, :class:`FleetManeuver`, so every command passes
the loop's one safety pipeline (barrier, wheel limits, fail-stop, emergency stop) like any other
behaviour, whether the robots are simulated, MQTT GRITSBots, or both with virtual ones:

* :func:`set_up` — start poses ``(N, 3)`` (:func:`read_poses_csv`, or :func:`random_start_poses`)
  are checked (inside the arena, apart by the safety distance, clear of the robots that stay
  docked; :func:`swarmdeck.devices.fleet.setup.check_start_poses`), N charged, healthy robots are
  assigned (:func:`swarmdeck.devices.fleet.assignment.assign`: least total travel; robots whose
  battery is low or reads NaN, or that are not tracked, are named when too few remain), and the
  fleet's :class:`~swarmdeck.devices.fleet.maneuver.Maneuver` (pose control + deadlock escape)
  drives them;
* :func:`return_to_chargers` — every robot on the floor gets a free charger slot and docks
  (:func:`swarmdeck.devices.fleet.docking.choose_slots` and ``return_maneuver``: least total
  travel, approach pose, then backing onto the strip).

Robots that do not take part are fixed obstacles of the barrier (``FleetManeuver.fixed``): a docked
robot is never pushed off its strip. ``FleetManeuver`` is a thin behaviour over one
:class:`~swarmdeck.devices.fleet.task.UpkeepTask`, the task ``FleetManager`` drives too, which holds the
rules below. A maneuver that cannot finish in ``time_limit`` s of run time,
or loses a robot (no fresh pose for ``lost_after`` s, or gone from the reading), stops every robot
and names the robots (a ``BehaviourError`` each tick, shown as the loop's alert, until the operator
chooses another behaviour). Progress is the behaviour's health line (in every Frame).
"""
from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.console.runtime.behaviours import BehaviourError, TickInput
from swarmdeck.core.bounds import Bounds
from swarmdeck.core.checks import require_positive
from swarmdeck.core.constants import SAFETY_DISTANCE
from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.core.obstacles import START_CLEARANCE, Obstacles
from swarmdeck.core.ports import ReportsRobotHealth, rows_of
from swarmdeck.devices.battery import BatteryParams, charge_from_voltage
from swarmdeck.devices.chargers import ChargerLayout
from swarmdeck.devices.fleet.assignment import assign
from swarmdeck.devices.fleet.docking import choose_slots, return_maneuver
from swarmdeck.devices.fleet.manager import FleetConfig
from swarmdeck.devices.fleet.maneuver import Maneuver
from swarmdeck.devices.fleet.setup import ACCEPT_HEADING, ACCEPT_POSITION, check_start_poses
from swarmdeck.devices.fleet.task import LOOP_WORDING, UpkeepTask
from swarmdeck.devices.initial_conditions import random_initial_poses

FloatArray = NDArray[np.float64]
SET_UP, RETURN = "set up", "return to chargers"


@dataclass(frozen=True)
class UpkeepConfig:
    """Limits of the console's set-up and return.

    Attributes:
        fleet: the fleet's settings (:class:`~swarmdeck.devices.fleet.manager.FleetConfig`): the
            battery model, which robots may be assigned (charge ≥ ``min_charge``, tracked, firmware
            heard), the maneuvers' tolerances and deadlock escape, their barrier gain γ (linear κ:
            the maneuvers are tuned for it; the console's cubic κ with γ = 100 holds robots backing
            onto a strip near the wall too hard) and their time limit, base + N · per robot s. Its
            ``layout`` is not used: the console's charging strips follow its arena.
        time_limit: overrides the fleet's time limit, s of run time (None: the fleet's for N robots).
        lost_after: a moving robot without a fresh pose for this many s stops the maneuver.
    """

    fleet: FleetConfig = field(default_factory=FleetConfig)
    time_limit: float | None = None
    lost_after: float = 1.0

    def __post_init__(self) -> None:
        require_positive(self, ("lost_after",), "s")
        if self.time_limit is not None:
            require_positive(self, ("time_limit",), "s")

    def limit(self, n: int) -> float:
        """The time limit of a maneuver of ``n`` robots, s."""
        return self.fleet.time_limit(n) if self.time_limit is None else float(self.time_limit)

    @property
    def barrier(self) -> dict[str, Any]:
        """The barrier settings a maneuver runs with (``ControlLoop.use_behaviour``)."""
        return {"class_k": "linear", "gamma": self.fleet.gamma, "safety_distance": self.fleet.safety_distance}


@dataclass(frozen=True)
class FleetView:
    """The robots as the loop last saw them (a Frame's fields), for planning a maneuver.

    ids ``(M,)``, poses ``(M, 3)``, seen ``(M,)``, battery ``(M,)`` V (NaN: unknown),
    charging ``(M,)``, is_virtual ``(M,)``; ``status_age`` ``(M,)`` s since each robot's firmware
    last reported (0 for robots without firmware: simulated, virtual); ``firmware`` ``(M,)`` the
    robots that have firmware reporting their battery (the MQTT robots).
    """

    ids: NDArray[np.int64]
    poses: FloatArray
    seen: NDArray[np.bool_]
    battery: FloatArray
    charging: NDArray[np.bool_]
    is_virtual: NDArray[np.bool_]
    status_age: FloatArray
    firmware: NDArray[np.bool_]

    @classmethod
    def of(cls, frame: Any, status_age: ArrayLike | None = None) -> FleetView:
        """From a Frame (or anything with its per-robot fields); ``status_age`` None: robots without
        firmware reports (simulated)."""
        n = len(frame.ids)
        virtual = np.asarray(frame.is_virtual, dtype=bool)
        firmware = np.zeros(n, dtype=bool) if status_age is None else ~virtual
        age = np.zeros(n) if status_age is None else np.asarray(status_age, dtype=float).reshape(n)
        return cls(np.asarray(frame.ids, dtype=np.int64), np.asarray(frame.poses, dtype=float),
                   np.asarray(frame.seen, dtype=bool), np.asarray(frame.battery, dtype=float),
                   np.asarray(frame.charging, dtype=bool), virtual, age, firmware)

    def charge(self, battery: BatteryParams) -> FloatArray:
        """State of charge ``(M,)`` from the voltage. Robots that cannot report a battery count as full:
        virtual ones, and simulated robots when none of them has a battery model. A robot with firmware
        (MQTT), or among robots that report, with no valid reading is NaN: never assigned ("battery
        reads NaN")."""
        q = charge_from_voltage(self.battery, battery)
        some_report = bool((~np.isnan(q) & ~self.is_virtual).any())
        return np.where(self.is_virtual | (~self.firmware & np.isnan(q) & (not some_report)), 1.0, q)


class FleetManeuver:
    """Robots ``ids`` driven by a :class:`Maneuver` through the console loop (module docstring): a thin
    behaviour over one :class:`~swarmdeck.devices.fleet.task.UpkeepTask` (time limit, lost robots,
    progress, messages — the rules ``FleetManager`` applies too), whose failures are the loop's
    ``BehaviourError``.

    Args:
        name: ``"set up"`` or ``"return to chargers"`` (the Frame's behaviour).
        ids: ``(K,)`` robot ids of the moving robots, in the maneuver's row order.
        maneuver: goals and controller.
        config: time limit, lost-robot timeout, barrier gains.
    """

    def __init__(self, name: str, ids: ArrayLike, maneuver: Maneuver, config: UpkeepConfig = UpkeepConfig()) -> None:
        n = len(np.asarray(ids).reshape(-1))
        self.task = UpkeepTask(name, ids, maneuver, time_limit=config.limit(n), lost_after=config.lost_after,
                               wording=LOOP_WORDING)
        self.name, self.ids, self.maneuver, self.config = name, self.task.ids, maneuver, config
        self.barrier = config.barrier
        self.time_limit = self.task.time_limit

    # ------------------------------------------------------------------ the task's state
    @property
    def state(self) -> str:
        """``"running"``, ``"done"`` or ``"failed"``."""
        return self.task.state

    @property
    def message(self) -> str:
        """Progress while running, the outcome once over."""
        return self.task.message

    @property
    def elapsed(self) -> float:
        """s of run time since the maneuver's first tick."""
        return self.task.elapsed

    @property
    def at_goal(self) -> NDArray[np.bool_]:
        """``(K,)`` robots at their goal at the last tick."""
        return self.task.at_goal

    @property
    def final_errors(self) -> tuple[float, float] | None:
        """(m, rad) largest errors once done, else None."""
        return self.task.final_errors

    # ------------------------------------------------------------------ behaviour protocol
    def fixed(self, ids: ArrayLike) -> NDArray[np.bool_]:
        """Robots that do not move in this maneuver (all of them once it is over): fixed obstacles."""
        ids = np.asarray(ids, dtype=np.int64).reshape(-1)
        if self.state != "running":
            return np.ones(len(ids), dtype=bool)
        return ~np.isin(ids, self.ids)

    def health(self) -> str:
        return self.message

    def __call__(self, tick: TickInput) -> tuple[FloatArray, None]:
        n = len(tick.poses)
        ids = np.arange(n, dtype=np.int64) if tick.ids is None else np.asarray(tick.ids, dtype=np.int64)
        seen = np.ones(n, dtype=bool) if tick.seen is None else np.asarray(tick.seen, dtype=bool)
        if self.state == "failed":
            raise BehaviourError(self.message)
        u = np.zeros((n, 2))
        if self.state == "done":
            return u, None
        rows, present = rows_of(ids, self.ids)
        poses = tick.poses[rows] if n else np.zeros((len(self.ids), 3))  # no robot at all: every one is lost
        nominal = self.task.update(tick.t, poses, present, seen[rows] if n else present)
        if self.state == "failed":
            raise BehaviourError(self.message)
        if nominal is not None:
            u[rows] = nominal
        return u, None


def status_ages(sink: object, view_ids: ArrayLike, is_virtual: ArrayLike) -> FloatArray | None:
    """``(M,)`` s since each robot's firmware last reported (the sink's ``robot_health()``, as
    ``NetworkRobots`` gives it; inf: never), 0 for virtual robots; None when the robots have no
    firmware (a simulation)."""
    ids = np.asarray(view_ids, dtype=np.int64).reshape(-1)
    if not isinstance(sink, ReportsRobotHealth):
        return None
    table = sink.robot_health()
    ages = np.array([(table.get(str(int(i))) or {}).get("status_age") for i in ids.tolist()], dtype=object)
    out = np.array([np.inf if a is None else float(a) for a in ages.tolist()], dtype=float)
    return np.where(np.asarray(is_virtual, dtype=bool), 0.0, out)


# ---------------------------------------------------------------------------- start poses
def read_poses_csv(path: str | Path | None = None, text: str | None = None) -> FloatArray:
    """Start poses ``(N, 3)`` ``[x, y, θ]`` (m, m, rad) from a CSV file (or its ``text``): one robot
    per row, three numbers; an optional header row (``x,y,theta``) and ``#`` comments are skipped.

    Raises ValueError naming the file, line and what is wrong (unreadable, not three numbers, not
    finite, no rows).
    """
    name = str(path) if path is not None else "start poses"
    if text is None:
        try:
            text = Path(path).read_text(encoding="utf-8")  # type: ignore[arg-type]
        except (OSError, UnicodeDecodeError) as exc:
            raise ValueError(f"{name}: cannot read: {getattr(exc, 'strerror', None) or exc}") from None
    rows: list[list[float]] = []
    for lineno, row in enumerate(csv.reader(io.StringIO(text)), start=1):  # a file of at most a few hundred rows
        cells = [c.strip() for c in row]
        if not cells or not any(cells) or cells[0].startswith("#"):
            continue
        if not rows and [c.lower() for c in cells[:3]] in (["x", "y", "theta"], ["x", "y", "θ"]):
            continue
        if len(cells) != 3:
            raise ValueError(f"{name}, line {lineno}: expected 3 values x, y, theta, got {len(cells)}: {row!r}")
        try:
            vals = [float(c) for c in cells]
        except ValueError:
            raise ValueError(f"{name}, line {lineno}: not numbers: {row!r} (expected x, y, theta in m, m, rad)") from None
        if not all(math.isfinite(v) for v in vals):
            raise ValueError(f"{name}, line {lineno}: x, y, theta must be finite, got {row!r}")
        rows.append(vals)
    if not rows:
        raise ValueError(f"{name}: no start poses (one line x, y, theta per robot)")
    return np.asarray(rows, dtype=float)


def random_start_poses(n: int, bounds: Bounds, chargers: ChargerLayout, seed: int | None = None) -> FloatArray:
    """``(N, 3)`` random start poses as rps generates them, kept clear of the charger slots' approach
    area (the robots that stay docked and the robots driving to their start poses)."""
    inner = chargers.dock_depth + chargers.approach_distance
    return random_initial_poses(int(n), Bounds.of(bounds).shrunk(inner), rng=seed)


# ---------------------------------------------------------------------------- planning
def set_up(view: FleetView, goals: ArrayLike, bounds: Bounds, chargers: ChargerLayout,
           robot: GritsBotParams = GritsBotParams(), safety_distance: float = SAFETY_DISTANCE,
           config: UpkeepConfig = UpkeepConfig(), obstacles: Obstacles | None = None) -> FleetManeuver:
    """A :class:`FleetManeuver` that sets N assigned robots up at ``goals`` ``(N, 3)``; robot k of the
    experiment is ``maneuver.ids[k]``; ``obstacles``: the floor's line segments (the maneuver routes round them;
    a goal on one is refused naming it).

    Raises ValueError naming the bad pose (outside, too close to another pose or to a docked robot)
    or, as :class:`~swarmdeck.devices.fleet.assignment.AssignmentError`, the robots left out and why
    when fewer than N are charged and healthy.
    """
    g = np.asarray(goals)
    if g.dtype.kind in "iu":
        g = g.astype(float)
    goals_arr = check_start_poses(g, bounds, robot, safety_distance=safety_distance)
    if obstacles is not None:
        obstacles.check_clear(goals_arr, START_CLEARANCE, "start pose")
    n = len(goals_arr)
    if n > len(view.ids):
        raise ValueError(f"{n} start poses but only {len(view.ids)} robots in the arena")
    pose_age = np.where(view.seen, 0.0, np.inf)
    a = assign(n, view.ids, view.charge(config.fleet.battery), pose_age, view.status_age, positions=view.poses[:, :2],
               goals=goals_arr, policy=config.fleet.policy)
    idle = a.idle
    if len(idle):  # the start poses must keep clear of the robots that stay where they are
        check_start_poses(goals_arr, bounds, robot, safety_distance=safety_distance, obstacles=view.poses[idle, :2],
                          obstacle_names=[f"robot {int(i)} (staying)" for i in view.ids[idle]])
    maneuver = Maneuver(goals_arr, bounds, robot, config.fleet.maneuver).route_around(obstacles)
    return FleetManeuver(SET_UP, view.ids[a.rows], maneuver, config)


def return_to_chargers(view: FleetView, bounds: Bounds, chargers: ChargerLayout,
                       robot: GritsBotParams = GritsBotParams(), config: UpkeepConfig = UpkeepConfig(),
                       ids: ArrayLike | None = None, obstacles: Obstacles | None = None) -> FleetManeuver:
    """A :class:`FleetManeuver` docking every robot on the floor (or only ``ids``) on a free charger slot
    (least total travel; docked robots keep theirs; round the line-segment ``obstacles``). ValueError when there
    are fewer free slots than robots to dock, or ``ids`` names robots the arena does not have."""
    slot = chargers.docked_slot(view.poses)
    floor = slot < 0
    if ids is not None:
        want = np.asarray(ids, dtype=np.int64).reshape(-1)
        unknown = np.setdiff1d(want, view.ids)
        if len(unknown):
            raise ValueError(f"no robot(s) {unknown.tolist()} in the arena (robots: {view.ids.tolist()})")
        floor &= np.isin(view.ids, want)
    rows = np.flatnonzero(floor)
    if not len(rows):
        return FleetManeuver(RETURN, view.ids[rows], _empty_maneuver(bounds, robot, config), config)
    free = np.setdiff1d(np.arange(chargers.n_slots), slot[slot >= 0])
    slots = choose_slots(view.poses[rows, :2], free, chargers)  # ValueError when too few are free
    fleet = config.fleet  # the plan keeps the operator's D_s and γ; robots staying docked hold their slots
    maneuver = return_maneuver(view.poses[rows], slots, chargers, robot, fleet.maneuver, occupied=slot[slot >= 0],
                               safety_distance=fleet.safety_distance, gamma=fleet.gamma,
                               retrace=obstacles is None).route_around(obstacles)  # the retrace plan knows none
    return FleetManeuver(RETURN, view.ids[rows], maneuver, config)


def _empty_maneuver(bounds: Bounds, robot: GritsBotParams, config: UpkeepConfig) -> Maneuver:
    return Maneuver(np.empty((0, 3)), bounds, robot, config.fleet.maneuver)


__all__ = ["ACCEPT_HEADING", "ACCEPT_POSITION", "FleetManeuver", "FleetView", "RETURN", "SET_UP", "UpkeepConfig",
           "UpkeepResult", "run_maneuver",
           "random_start_poses", "read_poses_csv", "return_to_chargers", "set_up", "status_ages"]


# ---------------------------------------------------------------------------- headless runs
@dataclass(frozen=True)
class UpkeepResult:
    """How a maneuver run by :func:`run_maneuver` ended.

    ok: every robot at its pose / docked. robots: the moving robots' ids (experiment order for a
    set-up). seconds: run time it took, s. max_position_error m / max_heading_error rad at the end
    (NaN when nobody moved). collisions: ticks with colliding robots (rps test; 0 expected).
    escapes: deadlock-escape goals handed out. message: the maneuver's last status line.
    """

    ok: bool
    robots: tuple[int, ...]
    seconds: float
    max_position_error: float
    max_heading_error: float
    collisions: int
    escapes: int
    message: str

    def to_dict(self) -> dict[str, Any]:
        def num(x: float) -> float | None:
            return float(x) if math.isfinite(x) else None

        return {"ok": self.ok, "robots": list(self.robots), "seconds": self.seconds,
                "max_position_error": num(self.max_position_error),
                "max_heading_error_deg": num(math.degrees(self.max_heading_error)),
                "collisions": self.collisions, "escapes": self.escapes, "message": self.message}


def run_maneuver(loop: Any, maneuver: FleetManeuver, pace: Any = None, max_ticks: int | None = None,
                 stop: Callable[[], bool] | None = None) -> UpkeepResult:
    """Run ``maneuver`` on ``loop`` (a ControlLoop, the same safety pipeline as the console) tick by
    tick until it is done or has failed (its time limit, a lost robot) or ``stop()`` says so (a cancel,
    an emergency stop: the result is not ok and says it was stopped); ``pace()`` is called after each
    tick (a real-time pacer for real robots; None: as fast as the simulation goes). The robots are
    stopped at the end either way (one zero command)."""
    from swarmdeck.devices.validation import colliding_pairs

    loop.use_behaviour(maneuver)
    loop.run()
    collisions, ticks = 0, 0
    frame = loop.latest
    stopped = False
    while maneuver.state == "running" and (max_ticks is None or ticks < max_ticks):
        if stop is not None and stop():
            stopped = True
            break
        frame = loop.tick()
        collisions += bool(len(colliding_pairs(frame.poses)))
        ticks += 1
        if pace is not None:
            pace()
    loop.estop()
    loop.tick()  # every robot gets zero
    err, head = maneuver.final_errors if maneuver.final_errors is not None else (math.nan, math.nan)
    if maneuver.state != "done" and frame is not None and len(maneuver.ids):
        rows, _ = rows_of(frame.ids, maneuver.ids)
        err_all, head_all = maneuver.task.errors(frame.poses[rows])
        err, head = float(err_all.max()), float(head_all.max())
    message = f"{maneuver.name} stopped before it finished ({maneuver.message})" if stopped else maneuver.message
    return UpkeepResult(maneuver.state == "done", tuple(int(i) for i in maneuver.ids), maneuver.elapsed, err, head,
                        collisions, int(maneuver.maneuver.escapes), message)
