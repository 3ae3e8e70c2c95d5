"""The fleet between experiments: robots on the chargers, assigned, set up, driven, returned.

:class:`FleetManager` ties the fleet's pieces together over a simulated arena that holds every
robot of the fleet (paper §III-A: the back end "assigns charged robots, sets them up to the
experiment's initial conditions, and returns them to the chargers afterwards"; REFERENCE.md §11):

1. the robots start docked on charger slots (:class:`~swarmdeck.devices.chargers.ChargerLayout`)
   and charge there (:mod:`~swarmdeck.devices.battery`);
2. :meth:`FleetManager.setup` assigns N charged, healthy robots to experiment ids 0…N−1
   (:func:`~swarmdeck.devices.fleet.assignment.assign`), checks the start poses
   (:func:`~swarmdeck.devices.fleet.setup.check_start_poses`) and drives the robots there under
   the barrier with the deadlock escape (:func:`~swarmdeck.devices.fleet.setup.drive`: one
   :class:`~swarmdeck.devices.fleet.task.UpkeepTask` over the fleet's own ports, :meth:`read`/:meth:`send`);
3. :meth:`FleetManager.experiment` is the experiment's view: N robots with ids 0…N−1 (a
   robot ports (:mod:`swarmdeck.core.ports`), what :class:`~swarmdeck.devices.Arena`
   drives), whose ``obstacles`` are the look-ahead points of the robots that stayed docked;
4. :meth:`FleetManager.return_to_chargers` docks every robot that is off its charger on a free
   slot; :meth:`FleetManager.ready` is True when every robot is docked or assigned.

The fleet's own maneuvers use a barrier with the paper's linear class-K function
(κ(h) = h, γ = 20, γ·dt ≤ 1 keeps the discrete loop safe, REFERENCE.md §3 and
:mod:`swarmdeck.safety.config`): rps's cubic κ lets two robots parked 0.24 m apart approach
each other at ~10⁻⁵ m/s, which would stall the last centimetres of a setup for minutes.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.constants import SAFETY_DISTANCE
from swarmdeck.core.kinematics import GritsBotParams, lookahead_points
from swarmdeck.core.obstacles import START_CLEARANCE
from swarmdeck.core.ports import SensedPoses
from swarmdeck.devices.battery import BatteryParams, battery_step, recharge
from swarmdeck.devices.chargers import ChargerLayout
from swarmdeck.devices.fleet.assigned import AssignedRobots
from swarmdeck.devices.fleet.assignment import Assignment, AssignmentPolicy, assign
from swarmdeck.devices.fleet.docking import choose_slots, return_maneuver
from swarmdeck.devices.fleet.maneuver import Maneuver, ManeuverParams
from swarmdeck.devices.fleet.routing import check_chargers_clear
from swarmdeck.devices.fleet.setup import ManeuverReport, check_start_poses, drive
from swarmdeck.devices.pipeline import barrier_filter
from swarmdeck.devices.simulator import ArenaConfig, SimulatedArena

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


@dataclass(frozen=True)
class FleetConfig:
    """How the fleet is kept (defaults: the 3.2 × 2 m arena, GRITSBots, REFERENCE.md §1).

    Attributes:
        layout: the charging strips and their slots (its bounds must be the arena's).
        battery: the battery model.
        policy: which robots may take part (charge, tracking, firmware).
        maneuver: tolerances, gains and the deadlock escape of setup and return.
        safety_distance: D_s between look-ahead points during setup and return, m.
        gamma: barrier gain of the fleet's maneuvers (linear κ; γ·dt ≤ 1).
        time_limit_base, time_limit_per_robot: a setup or return of N robots fails after
            base + N · per_robot simulated s.
    """

    layout: ChargerLayout = field(default_factory=ChargerLayout)
    battery: BatteryParams = field(default_factory=BatteryParams)
    policy: AssignmentPolicy = field(default_factory=AssignmentPolicy)
    maneuver: ManeuverParams = field(default_factory=ManeuverParams)
    safety_distance: float = SAFETY_DISTANCE
    gamma: float = 20.0
    time_limit_base: float = 60.0
    time_limit_per_robot: float = 2.0

    def time_limit(self, n: int) -> float:
        """Simulated s a setup or return of ``n`` robots may take."""
        return self.time_limit_base + n * self.time_limit_per_robot


class FleetManager:
    """A simulated fleet of M robots on the chargers of an arena (module docstring).

    Args:
        n_robots: M (default: one robot per charger slot).
        config: the arena (bounds, period); its ``seed`` picks the slots when M < slots.
        fleet: charger layout, battery, policy, maneuver settings.
        params: the robot model.
        charge: initial state of charge, scalar or ``(M,)`` in [0, 1] (NaN: unknown).
        slots: ``(M,)`` the slot each robot starts on (default: all slots, or a random subset).
    """

    def __init__(self, n_robots: int | None = None, *, config: ArenaConfig | None = None,
                 fleet: FleetConfig | None = None, params: GritsBotParams | None = None,
                 charge: ArrayLike = 1.0, slots: ArrayLike | None = None) -> None:
        self.config = config if config is not None else ArenaConfig()
        self.fleet = fleet if fleet is not None else FleetConfig(layout=ChargerLayout(bounds=self.config.bounds))
        self.params = params if params is not None else GritsBotParams()
        layout = self.fleet.layout
        if tuple(layout.bounds) != tuple(self.config.bounds):
            raise ValueError(f"the charger layout is for the arena {layout.bounds}, not {self.config.bounds}")
        layout.check_reachable(self.config.bounds, self.fleet.safety_distance, self.params.lookahead, self.params.radius)
        m_slots = layout.n_slots
        if slots is None:
            m = m_slots if n_robots is None else int(n_robots)
            if not 1 <= m <= m_slots:
                raise ValueError(f"a fleet of {m} robots needs 1..{m_slots} charger slots (the layout has {m_slots})")
            rng = np.random.default_rng(self.config.seed)
            slots = np.arange(m_slots) if m == m_slots else np.sort(rng.choice(m_slots, m, replace=False))
        slots = np.asarray(slots, dtype=np.intp).reshape(-1)
        if len(np.unique(slots)) != len(slots) or np.any((slots < 0) | (slots >= m_slots)):
            raise ValueError(f"slots must be distinct slot indices 0..{m_slots - 1}, got {slots.tolist()}")
        if n_robots is not None and len(slots) != n_robots:
            raise ValueError(f"{n_robots} robots but {len(slots)} slots given")
        check_chargers_clear(self.config.obstacles, layout)  # a slot on a segment could never be reached
        self.sim = SimulatedArena(initial_poses=layout.dock_poses()[slots], config=self.config, params=self.params)
        m = self.sim.n
        self.ids = np.arange(m, dtype=np.intp)
        self.charge = np.broadcast_to(np.asarray(charge, dtype=float), (m,)).copy()
        self.slot = slots.copy()  # (M,) slot each robot is docked on, −1 while away
        self.assignment: Assignment | None = None
        self.filter = barrier_filter(self.params, self.config.bounds, self.config.dt, class_k="linear",
                                     gamma=self.fleet.gamma, safety_distance=self.fleet.safety_distance,
                                     **({} if self.config.obstacles is None else {"obstacles": self.config.obstacles}))
        self.experiment_end: float | None = None  # fleet time the last experiment ended (return began)
        self.last_setup: ManeuverReport | None = None
        self.last_return: ManeuverReport | None = None
        self._experiment: AssignedRobots | None = None
        self._seen = np.ones(m, dtype=bool)

    # ------------------------------------------------------------------ state
    @property
    def n_robots(self) -> int:
        """M, robots in the fleet."""
        return self.sim.n

    @property
    def time(self) -> float:
        """Simulated s since the fleet was created."""
        return float(self.sim.time)

    def poses(self) -> FloatArray:
        """``(M, 3)`` poses of every robot (a copy)."""
        return self.sim.poses

    def docked(self) -> NDArray[np.bool_]:
        """``(M,)`` robots on a charger slot."""
        return self.slot >= 0

    def ready(self) -> bool:
        """Every robot is docked or assigned to an experiment (the arena can be left alone)."""
        assigned = np.zeros(self.n_robots, dtype=bool)
        if self.assignment is not None:
            assigned[self.assignment.rows] = True
        return bool(np.all(self.docked() | assigned))

    def status(self) -> list[dict[str, Any]]:
        """One JSON-able dict per robot: id, pose, charge, voltage, slot (−1: away), charging, experiment id."""
        exp = np.full(self.n_robots, -1)
        if self.assignment is not None:
            exp[self.assignment.rows] = np.arange(self.assignment.n)
        p, volts = self.poses(), self.fleet.battery.voltage(self.charge)
        keys = ("id", "x", "y", "theta", "charge", "voltage", "slot", "charging", "experiment_id")
        cols = (self.ids.tolist(), p[:, 0].tolist(), p[:, 1].tolist(), p[:, 2].tolist(), self.charge.tolist(),
                volts.tolist(), self.slot.tolist(), self.docked().tolist(), exp.tolist())
        return [dict(zip(keys, row)) for row in zip(*cols)]

    def _battery(self, sim: SimulatedArena, v: FloatArray, w: FloatArray) -> None:
        self.charge = battery_step(self.charge, sim.config.dt, v, w, self.docked(), self.params, self.fleet.battery)

    def wait(self, seconds: float) -> None:
        """Let ``seconds`` s pass between experiments with every robot standing still (docked ones charge)."""
        idle = battery_step(self.charge, seconds, np.zeros(self.n_robots), np.zeros(self.n_robots),
                            np.zeros(self.n_robots, dtype=bool), self.params, self.fleet.battery)
        self.charge = np.where(self.docked(), recharge(self.charge, seconds, self.fleet.battery), idle)

    # ------------------------------------------------------------------ setup
    def setup(self, goals: ArrayLike, *, time_limit: float | None = None, pose_age: ArrayLike = 0.0,
              status_age: ArrayLike = 0.0) -> ManeuverReport:
        """Assign ``len(goals)`` robots and drive them to the start poses ``goals`` ``(N, 3)``.

        ``pose_age``/``status_age`` ``(M,)`` s since tracking saw each robot / its firmware reported
        (0 for the simulated fleet). Robots not assigned stay docked and are obstacles.

        Raises:
            AssignmentError: fewer charged, healthy robots than N (each robot left out named).
            ValueError: a start pose outside the arena, too close to another or to a docked robot.
            SetupFailed: the time limit passed (robots stopped; those not at their pose named).
        """
        if self.assignment is not None:
            raise RuntimeError("the fleet is already set up for an experiment: return it to the chargers first")
        check: dict[str, Any] = dict(safety_distance=self.fleet.safety_distance)
        g = check_start_poses(goals, self.config.bounds, self.params, **check)
        if self.config.obstacles is not None:
            self.config.obstacles.check_clear(g, START_CLEARANCE, "start pose")
        a = assign(len(g), self.ids, self.charge, pose_age, status_age, positions=self.poses()[:, :2], goals=g,
                   policy=self.fleet.policy)
        idle_pts = lookahead_points(self.poses()[a.idle], self.params.lookahead)
        names = [f"robot {int(self.ids[k])} docked on charger slot {int(self.slot[k])} (it stays there)" for k in a.idle]
        goals_ok = check_start_poses(g, self.config.bounds, self.params, obstacles=idle_pts, obstacle_names=names,
                                     **check)
        man = Maneuver(goals_ok, self.config.bounds, self.params, self.fleet.maneuver).route_around(self.config.obstacles)
        self.assignment = a
        self.experiment_end = None
        self.slot[a.rows] = -1
        limit = self.fleet.time_limit(len(g)) if time_limit is None else float(time_limit)
        try:
            report = drive(self, man, a.rows, self.filter, time_limit=limit, labels=self.ids[a.rows], what="setup")
        finally:
            self._settle()
        self.last_setup = report
        return report

    def experiment(self) -> AssignedRobots:
        """The assigned robots as the experiment's robots 0…N−1 (after :meth:`setup`): robot ports over
        this fleet's (:meth:`read`, :meth:`send`) whose ``obstacles()`` are the look-ahead points of the
        robots that stayed docked and whose ``report`` counts the experiment's own validation errors;
        their clock starts at 0 and stands still once the fleet returns to the chargers."""
        if self.assignment is None:
            raise RuntimeError("no robots are assigned: call setup() first")
        self._experiment = AssignedRobots(self, self, self.ids[self.assignment.rows], self.params.lookahead,
                                          validate=(self.config.bounds, self.params))
        return self._experiment

    # ------------------------------------------------------------------ the fleet's robot ports
    name = "fleet"

    def read(self, now: float = 0.0) -> SensedPoses:
        """Every robot of the fleet (always seen), its battery and charging state, on the fleet's clock."""
        return SensedPoses(self.ids.astype(np.int64), self.sim.poses, self._seen,
                           battery=self.fleet.battery.voltage(self.charge), charging=self.docked(), time=self.sim.time)

    def send(self, ids: NDArray[np.int64], v: NDArray[np.float64], w: NDArray[np.float64]) -> None:
        """One period of ``(v, ω)`` for every robot of the fleet, in id order; batteries drain or charge."""
        if len(ids) != self.n_robots or np.any(np.asarray(ids) != self.ids):
            raise ValueError(f"the fleet expects commands for ids 0..{self.n_robots - 1} in order")
        self.sim.step(v, w)
        self._battery(self.sim, *self.sim.applied)

    @property
    def report(self) -> Any:
        """The simulator's validation counts (boundary, collisions, actuator limits) over every robot."""
        return self.sim.report

    def hold(self) -> None:
        """Nothing moves (the simulation does not advance)."""

    def health(self) -> str:
        return f"fleet clock {self.time:.1f} s, collision steps {self.sim.report.steps_with_collision}"

    def close(self) -> None:
        """Nothing to release."""

    # ------------------------------------------------------------------ return
    def return_to_chargers(self, *, time_limit: float | None = None) -> ManeuverReport:
        """Dock every robot that is off its charger on a free slot (nearest overall), safely.

        Raises:
            ValueError: more robots away than free slots.
            SetupFailed: the time limit passed (robots stopped; those not docked named).
        """
        away = np.flatnonzero(self.slot < 0)
        if self._experiment is not None:
            self._experiment.end()
            self._experiment = None
        self.assignment = None
        self.experiment_end = self.sim.time  # the experiment's clock stops here
        if len(away) == 0:
            return ManeuverReport(True, 0.0, 0.0, 0, 0.0, 0.0, 0)
        layout = self.fleet.layout
        free = np.setdiff1d(np.arange(layout.n_slots), self.slot[self.slot >= 0])
        poses = self.poses()
        slots = choose_slots(poses[away, :2], free, layout)
        obstacles = self.config.obstacles
        man = return_maneuver(poses[away], slots, layout, self.params, self.fleet.maneuver,
                              occupied=self.slot[self.slot >= 0], safety_distance=self.fleet.safety_distance,
                              gamma=self.fleet.gamma, dt=self.config.dt,
                              retrace=obstacles is None).route_around(obstacles)  # the retrace plan knows no obstacles
        limit = self.fleet.time_limit(len(away)) if time_limit is None else float(time_limit)
        try:
            report = drive(self, man, away, self.filter, time_limit=limit, labels=self.ids[away],
                           what="return to the chargers")
        finally:
            self._settle()
        self.last_return = report
        return report

    def _settle(self) -> None:
        """Robots found on a slot count as docked (and charge); the others as away."""
        on = self.fleet.layout.docked_slot(self.poses(), position_tolerance=0.02, heading_tolerance=0.1)
        assigned = np.zeros(self.n_robots, dtype=bool)
        if self.assignment is not None:
            assigned[self.assignment.rows] = True
        self.slot = np.where(assigned, -1, on)
