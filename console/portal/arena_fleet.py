"""The portal arena's fleet between jobs: M robots on the chargers, assigned, set up, returned, charging.

Paper §III-A/§III-C ("always on"): the back end assigns charged robots to each experiment, drives
them to its start poses, returns them to the charging strips afterwards and lets them charge, so an
operator can leave the arena alone. :class:`ArenaFleet` is that for the portal's
:class:`~swarmdeck.console.portal.runner.ArenaRunner`, over one of two kinds of robots:

* **simulated** (``robots_via`` None): ONE persistent
  :class:`~swarmdeck.devices.simulated_robots.SimulatedRobots` of M robots with batteries, docked on
  charger slots 0…M−1 when the server starts; it lives as long as the server;
* **networked** (``robots_via="mqtt://…"``): the MQTT fleet's robot ids 0…M−1
  (:class:`~swarmdeck.devices.net.console_robots.NetworkRobots`, connected when first needed and
  kept; GRITSBots or ``swarmdeck robots --start docked --charge``), whose firmware reports battery
  and charging. A robot that never reports is listed as missing and never assigned; the others work.

Both go through the same steps, each a
:class:`~swarmdeck.console.runtime.fleet_upkeep.FleetManeuver` run by
:func:`~swarmdeck.console.runtime.fleet_upkeep.run_maneuver` on a
:class:`~swarmdeck.console.runtime.loop.ControlLoop` over all M robots (the console's one safety
pipeline; the robots that do not move are fixed obstacles of the barrier):

1. :meth:`ArenaFleet.shortfall` — can N robots be assigned now (charged ≥ ``min_charge``, tracked,
   firmware heard)? If not, the reason, naming each robot left out;
2. :meth:`ArenaFleet.set_up` — assign N robots (least total travel) and drive them to the start
   poses; on success the experiment's ports, :class:`~swarmdeck.devices.fleet.assigned.AssignedRobots`
   (robots 0…N−1; the others are the barrier's obstacles);
3. :meth:`ArenaFleet.return_all` — every robot on the floor backs onto a free charger slot;
4. :meth:`ArenaFleet.idle` — between jobs docked simulated robots charge for the wall time that
   passed (networked robots charge by themselves, their firmware reports it).

The maneuvers run in real time, one control period per tick, as the jobs do (the networked fleet's always;
the simulated fleet's unless ``fast``, ``swarmdeck server --fast``, where they are computed as fast as they go).

:meth:`ArenaFleet.status` (any thread) is the fleet table: per robot its state (``docked``,
``charging``, ``assigned`` to job X, ``away``), charge, voltage and slot, and ``ready`` (every robot
docked or assigned), from the newest reading the arena thread made.
"""
from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.console.runtime import fleet_upkeep as fu
from swarmdeck.console.runtime.batteries import battery_levels
from swarmdeck.console.runtime.hardware import RobotsSpec, open_robots
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.core.bounds import Bounds
from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.core.obstacles import Obstacles
from swarmdeck.core.ports import SensedPoses
from swarmdeck.devices.battery import recharge
from swarmdeck.devices.chargers import ChargerLayout
from swarmdeck.devices.fleet.assigned import AssignedRobots
from swarmdeck.devices.fleet.assignment import AssignmentError, assign
from swarmdeck.devices.simulated_robots import SimulatedRobots

LoopHook = Callable[[ControlLoop | None], None]


class ArenaFleet:
    """The arena's M robots between jobs (module docstring).

    Args:
        n_robots: M (at most the charger layout's slots).
        bounds, dt: the arena and its control period.
        robots_via: ``mqtt://HOST:PORT`` of the networked fleet (ids 0…M−1); None: simulated.
        seed: seed of the simulated arena (and of random start poses).
        charge: the simulated robots' state of charge at start, scalar or ``(M,)`` ∈ [0, 1].
        config: the maneuvers' limits and the assignment policy.
        wait_for_poses: networked fleet: s to wait for every robot's first pose when connecting.
        fast: simulated fleet: compute the maneuvers as fast as they go instead of in real time.
        obstacles: the floor's line-segment obstacles (solid for simulated robots, in every loop's barrier; the
            maneuvers route round them).
    """

    def __init__(self, n_robots: int, bounds: Bounds, dt: float, *, robots_via: str | None = None,
                 seed: int | None = None, charge: ArrayLike = 1.0, config: fu.UpkeepConfig = fu.UpkeepConfig(),
                 robot: GritsBotParams | None = None, wait_for_poses: float = 5.0, fast: bool = False,
                 obstacles: Obstacles | None = None) -> None:
        self.obstacles = obstacles
        self.chargers = ChargerLayout(bounds=bounds)
        m = int(n_robots)
        if not 1 <= m <= self.chargers.n_slots:
            raise ValueError(f"a fleet of {m} robots needs 1..{self.chargers.n_slots} charger slots "
                             f"(the arena's charging strips have {self.chargers.n_slots})")
        self.bounds, self.dt, self.seed, self.fast = bounds, float(dt), seed, bool(fast)
        self.robots_via, self.config, self.wait_for_poses = robots_via, config, float(wait_for_poses)
        self.robot = robot if robot is not None else GritsBotParams()
        self.ids = np.arange(m, dtype=np.int64)
        self.sim: SimulatedRobots | None = None
        if robots_via is None:  # no robots_via: open_robots opens a SimulatedRobots (one object, source and sink)
            charges = np.broadcast_to(np.asarray(charge, dtype=float), (m,))
            self.sim = cast(SimulatedRobots, open_robots(replace(self._spec(), charge=tuple(charges.tolist()))).sink)
        self._net: Any = None
        self._lock = threading.Lock()
        self._reading: SensedPoses | None = None
        self._assigned: dict[int, int] = {}  # fleet id -> job id
        self.error: str | None = None  # why the networked fleet cannot be reached (None: fine)
        self.frame_listeners: list[Callable[[Any], None]] = []  # also shown the maneuvers' Frames (the operator's view)
        self._starts = 0

    @property
    def n_robots(self) -> int:
        return len(self.ids)

    @property
    def real_time(self) -> bool:
        """Maneuvers run in real time (networked robots; simulated ones unless ``fast``)."""
        return self.robots_via is not None or not self.fast

    # ------------------------------------------------------------------ ports
    def ports(self) -> tuple[Any, Any]:
        """The fleet's pose source and command sink (connecting to the networked fleet when needed).

        Raises ValueError when the networked fleet cannot be reached (no pose from every robot in time).
        """
        if self.sim is not None:
            return self.sim, self.sim
        if self._net is None:
            try:
                self._net = self._connect()
            except (ValueError, OSError) as exc:
                self.error = f"cannot reach the robots: {exc}"
                raise ValueError(self.error) from None
            self.error = None
        return self._net[1], self._net[0]

    def _spec(self) -> RobotsSpec:
        """The fleet's robots for the one robots factory: M simulated robots docked on slots 0…M−1 with
        batteries, or the networked fleet's ids 0…M−1 (going on with those that report in time)."""
        return RobotsSpec(n_robots=self.n_robots, bounds=self.bounds, dt=self.dt, seed=self.seed,
                          robots_via=self.robots_via, docked=self.robots_via is None,
                          wait_for_poses=self.wait_for_poses, partial=True, params=self.robot,
                          obstacles=self.obstacles)

    def _connect(self) -> tuple[Any, Any]:
        """The networked fleet's ports once every robot sent a pose, or at least one did within
        ``wait_for_poses`` s (ValueError: none did). Robots that have not (yet) reported are left out of
        readings and never assigned: one silent robot does not keep the arena from working (the table
        lists it as missing)."""
        ports = open_robots(self._spec())
        return ports.sink, ports.source

    def close(self) -> None:
        """Disconnect the networked fleet (robots commanded zero first); nothing for a simulation."""
        net, self._net = self._net, None
        if net is not None:
            net[0].close()

    def read(self) -> SensedPoses:
        """A fresh reading of every robot (kept for :meth:`status`). ValueError: fleet unreachable."""
        source, _ = self.ports()
        reading = source.read(time.monotonic())
        self._note(reading)
        return reading

    def _note(self, reading: SensedPoses) -> None:
        with self._lock:
            self._reading = reading

    def _loop(self) -> tuple[ControlLoop, Any]:
        """A control loop over all M robots for a maneuver (paused), and its pacer (None: unpaced)."""
        from swarmdeck.devices.clock import RealTimePacer

        source, sink = self.ports()
        cfg = LoopConfig(n_robots=self.n_robots, dt=self.dt, bounds=self.bounds, seed=self.seed,
                         behaviour="rendezvous", obstacles=self.obstacles)
        loop = ControlLoop(cfg, source=source, sink=sink, clock=time.monotonic if self.real_time else None,
                           robot=self.robot)
        loop.subscribe(self._note_frame)
        for listener in self.frame_listeners:
            loop.subscribe(listener)
        loop.pause()
        return loop, (RealTimePacer(self.dt).wait if self.real_time else None)

    def _note_frame(self, frame: Any) -> None:
        self._note(SensedPoses(frame.ids, frame.poses, frame.seen, frame.is_virtual, frame.battery, frame.charging))

    def _view(self, reading: Any, sink: Any) -> fu.FleetView:
        n = len(reading.ids)
        virtual = np.zeros(n, dtype=bool) if reading.is_virtual is None else np.asarray(reading.is_virtual, bool)
        battery = np.full(n, np.nan) if reading.battery is None else reading.battery
        charging = np.zeros(n, dtype=bool) if reading.charging is None else reading.charging
        frame = SensedPoses(reading.ids, reading.poses, reading.seen, virtual, battery, charging)
        return fu.FleetView.of(frame, fu.status_ages(sink, frame.ids, virtual))

    # ------------------------------------------------------------------ the steps
    def shortfall(self, n: int) -> str | None:
        """None when ``n`` robots can be assigned now; else why not (each robot left out named)."""
        try:
            reading = self.read()
            _, sink = self.ports()
        except ValueError as exc:
            return str(exc)
        view = self._view(reading, sink)
        try:
            assign(int(n), view.ids, view.charge(self.config.fleet.battery), np.where(view.seen, 0.0, np.inf),
                   view.status_age, policy=self.config.fleet.policy)
        except AssignmentError as exc:
            missing = np.setdiff1d(self.ids, view.ids)
            return str(exc) + (f"; never heard from robot(s) {', '.join(map(str, missing.tolist()))}"
                               if len(missing) else "")
        return None

    def start_poses(self, n: int) -> NDArray[np.float64]:
        """``(n, 3)`` random valid start poses, clear of the chargers' approach area (a fresh draw per job)."""
        self._starts += 1
        seed = None if self.seed is None else self.seed + self._starts
        return fu.random_start_poses(n, self.bounds, self.chargers, seed)

    def set_up(self, job_id: int, goals: ArrayLike, *, stop: Callable[[], bool], on_loop: LoopHook
               ) -> tuple[fu.UpkeepResult, AssignedRobots | None]:
        """Assign ``len(goals)`` robots to job ``job_id`` and drive them to ``goals`` ``(N, 3)``.

        Returns the maneuver's result and, when it succeeded, the experiment's robot ports (robots
        0…N−1 = ``result.robots``). ``on_loop(loop)`` is told the maneuver's loop (for an emergency stop)
        and None after it. Raises ValueError (an AssignmentError among them) naming the bad pose or the
        robots left out; nothing moved then.
        """
        loop, pace = self._loop()
        source, sink = self.ports()
        frame = loop.tick()
        maneuver = fu.set_up(self._view(frame, sink), goals, self.bounds, self.chargers, self.robot,
                             self.config.fleet.safety_distance, self.config, obstacles=frame.obstacles)
        with self._lock:
            self._assigned = {int(i): int(job_id) for i in maneuver.ids}
        result = self._run(loop, maneuver, pace, stop, on_loop)
        if not result.ok:
            return result, None
        return result, AssignedRobots(source, sink, result.robots, self.robot.lookahead, on_read=self._note)

    def end_assignment(self) -> None:
        """The job is over: its robots are no longer assigned (they are ``away`` until they dock)."""
        with self._lock:
            self._assigned = {}

    def return_all(self, *, stop: Callable[[], bool], on_loop: LoopHook) -> fu.UpkeepResult:
        """Every robot on the floor to a free charger slot; the assignment ends. Raises ValueError when
        there are fewer free slots than robots on the floor, or the fleet cannot be reached."""
        self.end_assignment()
        loop, pace = self._loop()
        _, sink = self.ports()
        frame = loop.tick()
        maneuver = fu.return_to_chargers(self._view(frame, sink), self.bounds, self.chargers, self.robot, self.config,
                                         obstacles=frame.obstacles)
        return self._run(loop, maneuver, pace, stop, on_loop)

    def _run(self, loop: ControlLoop, maneuver: fu.FleetManeuver, pace: Any, stop: Callable[[], bool],
             on_loop: LoopHook) -> fu.UpkeepResult:
        on_loop(loop)
        try:
            return fu.run_maneuver(loop, maneuver, pace, stop=stop)
        finally:
            on_loop(None)

    def away(self) -> list[int]:
        """Robot ids neither docked nor assigned to a job, from a fresh reading (raises ValueError:
        fleet unreachable)."""
        reading = self.read()
        slot = self.chargers.docked_slot(reading.poses)
        with self._lock:
            assigned = set(self._assigned)
        return [int(i) for i, s in zip(reading.ids.tolist(), slot.tolist()) if s < 0 and int(i) not in assigned]

    def idle(self, seconds: float) -> None:
        """``seconds`` s pass between jobs: docked simulated robots charge (networked ones charge by themselves)."""
        sim = self.sim
        if sim is None or sim.charge is None or not seconds > 0:
            return
        with self._lock:  # one update at a time (the arena thread, or a test standing in for the hours)
            sim.charge = np.where(sim.docked(), recharge(sim.charge, seconds, sim.battery), sim.charge)

    # ------------------------------------------------------------------ the table (any thread)
    def status(self) -> dict[str, Any]:
        """``{"robots": [rows], "ready", "docked", "size", "assigned": {id: job}, "error"}``; each row ``id``,
        ``state`` (docked | charging | assigned | away | not seen | missing: never heard from), ``job``
        (assigned), ``charge`` ∈ [0, 1] or None, ``voltage`` V or None, ``slot`` or None, ``x``, ``y``, ``theta``
        (m, rad); ``bounds`` ``[x0, x1, y0, y1]`` m, the arena (the operator page draws the fleet on it)."""
        with self._lock:
            reading, assigned = self._reading, dict(self._assigned)
        if reading is None:
            return {"robots": [], "ready": False, "docked": 0, "assigned": {}, "error": self.error,
                    "size": self.n_robots, "bounds": [float(v) for v in self.bounds]}
        n = len(reading.ids)
        volts = np.full(n, np.nan) if reading.battery is None else np.asarray(reading.battery, dtype=float)
        charging = np.zeros(n, dtype=bool) if reading.charging is None else np.asarray(reading.charging, dtype=bool)
        q, _ = battery_levels(volts, charging)
        slot = self.chargers.docked_slot(reading.poses)
        rows: list[dict[str, Any]] = []
        for k, rid in enumerate(reading.ids.tolist()):  # a table for people, on request
            job = assigned.get(int(rid))
            if job is not None:
                state = "assigned"
            elif slot[k] >= 0:
                state = "charging" if charging[k] and not q[k] >= 0.995 else "docked"
            else:
                state = "away" if reading.seen[k] else "not seen"
            rows.append({"id": int(rid), "state": state, "job": job,
                         "charge": float(q[k]) if math.isfinite(q[k]) else None,
                         "voltage": float(volts[k]) if math.isfinite(volts[k]) else None,
                         "slot": int(slot[k]) if slot[k] >= 0 else None,
                         "x": float(reading.poses[k, 0]), "y": float(reading.poses[k, 1]),
                         "theta": float(reading.poses[k, 2])})
        for rid in np.setdiff1d(self.ids, reading.ids).tolist():  # never heard of (networked fleet)
            rows.append({"id": int(rid), "state": "missing", "job": None, "charge": None, "voltage": None,
                         "slot": None, "x": None, "y": None, "theta": None})
        rows.sort(key=lambda r: r["id"])
        docked = sum(r["slot"] is not None and r["job"] is None for r in rows)
        ready = all(r["state"] in ("docked", "charging", "assigned") for r in rows)
        return {"robots": rows, "ready": ready, "docked": docked, "assigned": {str(k): v for k, v in assigned.items()},
                "error": self.error, "size": self.n_robots, "bounds": [float(v) for v in self.bounds]}
