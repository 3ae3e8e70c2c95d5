"""One floor, several experiments at once: region-local robot ports and one barrier over every robot.

:class:`SharedFloor` owns the floor's robot ports (a pose source and command sink of
:mod:`swarmdeck.core.ports` over all M robots, e.g. :class:`~swarmdeck.devices.simulated_robots.SimulatedRobots`)
and a :class:`~swarmdeck.devices.fleet.regions.RegionLayout`. A job placed in region R gets
:meth:`SharedFloor.open_region` → :class:`RegionRobots`, both robot ports over the floor:

* ``read`` — its N robots as ids 0…N−1 in R's frame (poses translated by R's origin, θ unchanged), the
  time since the region opened; an unmodified script cannot tell it shares the floor;
* ``send(ids, v, w)`` — its unicycle commands for the next period (a translation leaves ``(v, ω)``
  unchanged), held until the floor's tick;
* ``obstacles`` — the look-ahead points of every other robot on the floor, in R's frame;
* ``close`` — one period of zero commands; ``leave`` — the region leaves the floor's ticks (its robots stand
  still, fixed points of the barrier).

**The tick** (lockstep: it runs, on the thread of the last region to send, once every open region sent
its period's commands): the commands of all regions are put together (robots of no open region, and of a
stopped region, get zero and are the barrier's fixed points), ONE barrier certifies every moving robot on
the floor together (:func:`swarmdeck.devices.pipeline.certify`) with per-robot wall rows at each robot's
region bounds (:meth:`RegionLayout.robot_bounds`), and the floor's sink sends them once. So a job's robots
never leave their region and never come closer than D_s (look-ahead points) to another job's robots,
whatever either script commands. If the barrier fails, every robot is stopped for that tick.

An emergency stop (:meth:`SharedFloor.estop`) stops one region (its robots zero and fixed from the next
tick) or the whole floor. :attr:`SharedFloor.stats` counts ticks, barrier failures, robots outside their
region (centre outside, should stay 0) and the closest two robots of different regions came.
"""
from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.constants import CONTROL_PERIOD, SAFETY_DISTANCE
from swarmdeck.core.errors import SwarmdeckError
from swarmdeck.core.kinematics import GritsBotParams, lookahead_points, unicycle_to_si
from swarmdeck.core.ports import SensedPoses, rows_of
from swarmdeck.devices.fleet.regions import Region, RegionLayout
from swarmdeck.devices.initial_conditions import lattice_sites
from swarmdeck.devices.pipeline import barrier_filter, certify
from swarmdeck.devices.simulated_robots import SimulatedRobots
from swarmdeck.devices.simulator import ArenaConfig

FloatArray = NDArray[np.float64]


#: m between parked simulated robots (:func:`simulated_floor`): wide enough to drive back between neighbours
PARKING_SPACING = 0.3
#: wall s the floor's other regions wait for one region's commands of a tick before that region is stopped as
#: stalled (:meth:`SharedFloor.stall`): a script that stops answering (it sleeps, blocks, or answers just inside its
#: own per-tick wall backstop) must not hold the other regions' jobs up to its wall-time limit
STALL_LIMIT_S = 5.0


class FloorClosed(RuntimeError, SwarmdeckError):
    """The floor was closed (or its region ended) while a job waited for its tick."""


@dataclass
class FloorStats:
    """What the floor's ticks measured (all robots, floor frame).

    ticks: periods run; barrier_failures: ticks the barrier failed (every robot stopped);
    outside: robot-ticks with a robot's centre outside its region's rectangle (0 expected);
    min_between_regions: the smallest distance between the centres of two robots of different regions, m;
    stopped: regions stopped by an emergency stop (or as stalled);
    stalled: regions stopped because the others waited more than ``stall_s`` for their commands (one entry per stall).
    """

    ticks: int = 0
    barrier_failures: int = 0
    outside: int = 0
    min_between_regions: float = math.inf
    stopped: list[str] = field(default_factory=list)
    stalled: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        d = self.min_between_regions
        return {"ticks": self.ticks, "barrier_failures": self.barrier_failures, "outside": self.outside,
                "min_between_regions_m": None if not math.isfinite(d) else round(d, 4), "stopped": list(self.stopped),
                "stalled": list(self.stalled)}


class SharedFloor:
    """Several region jobs on one floor's ports, certified by one barrier (module docstring).

    Args:
        ports: the floor's pose source and command sink (one object), all robots.
        layout: the regions.
        params: the robot model.
        dt: the control period, s.
        safety_filter: the floor's barrier (default: :func:`~swarmdeck.devices.pipeline.barrier_filter` over the
            floor; its wall rows are replaced by each robot's region, robot by robot).
        on_tick: called on the ticking thread after every tick with the floor's reading (e.g. a floor-wide view).
        stall_s: wall s the other regions wait for one region's commands before it is stopped as stalled (the
            portal's :class:`~swarmdeck.console.portal.region_runner.RegionRunner`: :data:`STALL_LIMIT_S`); None: they
            wait as long as it takes (trusted in-process jobs, :func:`~swarmdeck.console.runtime.region_jobs.run_queue`,
            where a slow thread on a loaded machine is no stall).
        on_stall: called (on the waiting region's thread, outside the floor's lock) with a stalled region's name
            and why, e.g. to end its job (:class:`~swarmdeck.console.portal.region_runner.RegionRunner` fails it).
    """

    def __init__(self, ports: Any, layout: RegionLayout, *, params: GritsBotParams | None = None,
                 dt: float = CONTROL_PERIOD, safety_filter: Any = None,
                 on_tick: Callable[[SensedPoses], None] | None = None, stall_s: float | None = None,
                 on_stall: Callable[[str, str], None] | None = None) -> None:
        if stall_s is not None and not (math.isfinite(stall_s) and stall_s > 0):
            raise ValueError(f"stall_s must be a positive number of seconds, got {stall_s!r}")
        self.stall_s: float | None = None if stall_s is None else float(stall_s)
        self.on_stall = on_stall
        self.ports, self.layout = ports, layout
        self.params = params if params is not None else GritsBotParams()
        self.dt = float(dt)
        self.filter = safety_filter if safety_filter is not None else barrier_filter(
            self.params, layout.floor, self.dt, max_speed=self.params.max_speed)
        self.on_tick = on_tick
        self.stats = FloorStats()
        self._cv = threading.Condition()
        self._reading: SensedPoses = ports.read(0.0)
        self._open: dict[str, RegionRobots] = {}
        self._pending: dict[str, tuple[FloatArray, FloatArray]] = {}
        self._stopped: set[str] = set()
        self._all_stopped = False
        self._closed = False
        self._tick = 0

    # ------------------------------------------------------------------ regions
    def reading(self) -> SensedPoses:
        """The floor's latest reading (all robots, floor frame)."""
        with self._cv:
            return self._reading

    def busy(self) -> set[str]:
        """Regions with a job open now."""
        with self._cv:
            return set(self._open)

    def free_robots(self, name: str) -> NDArray[np.int64]:
        """Floor ids of the robots standing in region ``name`` that no open region holds, nearest its origin first."""
        region = self.layout.region(name)
        with self._cv:
            reading = self._reading
            taken = np.concatenate([r.fleet_ids for r in self._open.values()] or [np.zeros(0, dtype=np.int64)])
        ids = np.asarray(reading.ids, dtype=np.int64)
        poses = np.asarray(reading.poses, dtype=float)
        here = region.bounds.contains(poses) & ~np.isin(ids, taken) & np.asarray(reading.seen, dtype=bool)
        d = np.hypot(poses[:, 0] - region.origin[0], poses[:, 1] - region.origin[1])
        order = np.flatnonzero(here)[np.argsort(d[here], kind="stable")]
        return ids[order]

    def open_region(self, name: str, robots: int | ArrayLike, goals: ArrayLike | None = None) -> RegionRobots:
        """Region ``name``'s ports for a job: ``robots`` (a count: the free robots standing in the region, nearest
        its centre first; or floor ids) as robots 0…N−1 — with ``goals`` ``(N, 2+)`` (region frame, m: where the
        job's robots will be set up) ordered so that robot k is the one whose way to goal k is short (the
        assignment of least total distance: crossing paths deadlock under the barrier). ValueError when the
        region is busy, does not exist or has too few free robots."""
        region = self.layout.region(name)
        with self._cv:
            if self._closed:
                raise ValueError("the floor is closed")
            if name in self._open:
                raise ValueError(f"region {name} already runs a job")
        if isinstance(robots, (int, np.integer)):
            free = self.free_robots(name)
            if len(free) < int(robots):
                raise ValueError(f"region {name} has {len(free)} free robot(s), the job asks for {int(robots)}")
            fleet_ids = free[:int(robots)]
        else:
            fleet_ids = np.asarray(robots, dtype=np.int64).reshape(-1)
        if goals is not None:
            fleet_ids = self._assigned(region, fleet_ids, np.asarray(goals, dtype=float).reshape(len(fleet_ids), -1))
        view = RegionRobots(self, region, fleet_ids)
        with self._cv:
            if name in self._open:
                raise ValueError(f"region {name} already runs a job")
            clash = [n for n in self.layout.conflicts(name) if n in self._open]
            if clash:  # a nested layout: a region and one inside it (or around it) never run jobs at once
                raise ValueError(f"region {name} overlaps region {clash[0]}, which runs a job")
            self._open[name] = view
            self._stopped.discard(name)
        return view

    def _assigned(self, region: Region, fleet_ids: NDArray[np.int64], goals: FloatArray) -> NDArray[np.int64]:
        """``fleet_ids`` reordered so that robot k goes to ``goals[k]`` (region frame) on the assignment of least
        total distance (:func:`scipy.optimize.linear_sum_assignment`, once per job)."""
        from scipy.optimize import linear_sum_assignment

        reading = self.reading()
        rows, present = rows_of(reading.ids, fleet_ids)
        if not present.all():
            raise ValueError(f"region {region.name}: robots {fleet_ids[~present].tolist()} are not on the floor")
        here = region.to_local(np.asarray(reading.poses, dtype=float)[rows, :2])
        cost = np.linalg.norm(here[:, None, :] - goals[None, :, :2], axis=2)  # (N, N): N is one job's robots
        robot, goal = linear_sum_assignment(cost)
        out = np.empty_like(fleet_ids)
        out[goal] = fleet_ids[robot]
        return out

    def _leave(self, name: str) -> None:
        with self._cv:
            self._open.pop(name, None)
            self._pending.pop(name, None)
            self._cv.notify_all()
            self._maybe_tick()

    # ------------------------------------------------------------------ e-stop
    def estop(self, name: str | None = None) -> None:
        """Stop region ``name`` (its robots zero and fixed from the next tick), or the whole floor (None)."""
        with self._cv:
            if name is None:
                self._all_stopped = True
                self.stats.stopped = sorted(set(self.stats.stopped) | set(self._open))
            else:
                self.layout.region(name)
                self._stopped.add(name)
                if name not in self.stats.stopped:
                    self.stats.stopped.append(name)
            self._cv.notify_all()
            self._maybe_tick()  # the others may have been waiting for the stopped region's commands

    def release(self, name: str | None = None) -> None:
        """Undo :meth:`estop` for region ``name`` or the whole floor (None)."""
        with self._cv:
            if name is None:
                self._all_stopped = False
                self._stopped.clear()
            else:
                self._stopped.discard(name)

    def stopped(self, name: str) -> bool:
        with self._cv:
            return self._all_stopped or name in self._stopped

    def close(self) -> None:
        """End every region's waiting (they get :class:`FloorClosed`); the robots are stopped."""
        with self._cv:
            self._closed = True
            self._cv.notify_all()
        ids = np.asarray(self._reading.ids, dtype=np.int64)
        self.ports.send(ids, np.zeros(len(ids)), np.zeros(len(ids)))

    # ------------------------------------------------------------------ the tick
    def _submit(self, name: str, v: FloatArray, w: FloatArray) -> None:
        """Region ``name``'s commands for this period; returns once the floor ticked (lockstep)."""
        with self._cv:
            if self._closed:
                raise FloorClosed("the floor was closed")
            if name not in self._open:
                raise FloorClosed(f"region {name} is closed")
            target = self._tick + 1
            self._pending[name] = (v, w)
            self._maybe_tick()
            waited_from = time.monotonic()
            stalled: list[tuple[str, str]] = []
            while self._tick < target and not self._closed:
                left = math.inf if self.stall_s is None else waited_from + self.stall_s - time.monotonic()
                if left <= 0:
                    stalled.extend(self._stop_stalled(name))
                    waited_from = time.monotonic()
                    continue
                self._cv.wait(min(left, 1.0))
            closed = self._tick < target
        for stalled_name, why in stalled:  # outside the lock: the callback may stop or end the region's job
            if self.on_stall is not None:
                self.on_stall(stalled_name, why)
        if closed:
            raise FloorClosed("the floor was closed")

    def _stop_stalled(self, waiting: str) -> list[tuple[str, str]]:
        """Under the lock, after region ``waiting`` waited :attr:`stall_s` for this tick: the open regions running
        their job's script (:attr:`RegionRobots.watched`; set-ups and returns are the runner's own code) that did
        not send their commands are stopped (robots zero and fixed, as by :meth:`estop`) and counted in
        ``stats.stalled``, and the floor ticks without them; ``[(name, why)]``."""
        late = [n for n, view in self._open.items() if view.watched and n not in self._pending
                and not (self._all_stopped or n in self._stopped)]
        out = []
        for n in late:  # a handful of regions
            why = (f"region {n} stalled: its job sent no commands for {self.stall_s:g} s of wall time while region "
                   f"{waiting} waited for the floor's tick {self._tick + 1}; its robots were stopped and the other "
                   f"regions went on")
            self._stopped.add(n)
            if n not in self.stats.stopped:
                self.stats.stopped.append(n)
            self.stats.stalled.append(n)
            out.append((n, why))
        self._maybe_tick()
        return out

    def _maybe_tick(self) -> None:
        """Under the lock: tick when every open region that is not stopped sent its commands (a stopped region leaves
        the lockstep: its robots are zero and fixed, and its job may never send again — the others run on)."""
        if self._closed or not self._open or any(n not in self._pending for n in self._open
                                                  if not (self._all_stopped or n in self._stopped)):
            return
        if not self._pending:
            return
        try:
            self._step()
        finally:
            self._pending.clear()
            self._tick += 1
            self._cv.notify_all()

    def _step(self) -> None:
        reading = self._reading
        ids = np.asarray(reading.ids, dtype=np.int64)
        poses = np.asarray(reading.poses, dtype=float)
        n = len(ids)
        v, w = np.zeros(n), np.zeros(n)
        moving = np.zeros(n, dtype=bool)
        rows: dict[str, NDArray[np.intp]] = {}
        label = np.full(n, -1, dtype=np.int64)
        for k, (name, view) in enumerate(self._open.items()):  # one pass per region, vectorised inside
            r = view.rows(ids)
            rows[name] = r
            label[r] = k
            if name in self._pending and not (self._all_stopped or name in self._stopped):
                v[r], w[r] = self._pending[name]
                moving[r] = True
        moving &= np.asarray(reading.seen, dtype=bool)
        bounds = self.layout.robot_bounds(poses, rows)
        finite = np.where(np.isfinite(poses), poses, 0.0)
        nominal = unicycle_to_si(finite, v, w, self.params.lookahead)
        cert = certify(finite, nominal, self.params, self.filter, seen=moving, robot_bounds=bounds)
        if not cert.ok:
            self.stats.barrier_failures += 1
        self.ports.send(ids, np.where(cert.ok, cert.v, 0.0), np.where(cert.ok, cert.w, 0.0))
        self._reading = self.ports.read(0.0)
        self._measure(self._reading, rows, label)
        if self.on_tick is not None:
            self.on_tick(self._reading)

    def _measure(self, reading: SensedPoses, rows: dict[str, NDArray[np.intp]], label: NDArray[np.int64]) -> None:
        self.stats.ticks += 1
        xy = np.asarray(reading.poses, dtype=float)[:, :2]
        for name, r in rows.items():  # one pass per region
            self.stats.outside += int((~self.layout.region(name).bounds.contains(xy[r])).sum())
        placed = label >= 0
        if len(np.unique(label[placed])) >= 2:  # the closest robots of different regions (k-d tree, no N×N)
            pts = xy[placed]
            lab = label[placed]
            k = min(len(pts), 8)
            from scipy.spatial import cKDTree  # lazy: see test_devices_rps_startup_imports

            d, j = cKDTree(pts).query(pts, k=k)
            other = lab[j] != lab[:, None]
            if other.any():
                self.stats.min_between_regions = min(self.stats.min_between_regions, float(d[other].min()))


class RegionRobots:
    """A job's robots in its region: robot ports over the floor (module docstring of :mod:`.floor`).

    ``fleet_ids`` ``(N,)``: the floor ids; ``fleet_ids[k]`` is the job's robot k.
    """

    def __init__(self, floor: SharedFloor, region: Region, fleet_ids: ArrayLike) -> None:
        self.floor, self.region = floor, region
        self.fleet_ids = np.asarray(fleet_ids, dtype=np.int64).reshape(-1).copy()
        if not len(self.fleet_ids) or len(np.unique(self.fleet_ids)) != len(self.fleet_ids):
            raise ValueError(f"region {region.name}: the job's robots must be distinct floor ids, got "
                             f"{self.fleet_ids.tolist()}")
        self.n_robots = len(self.fleet_ids)
        self.name = f"region {region.name} (robots {', '.join(map(str, self.fleet_ids.tolist()))})"
        self._ids = np.arange(self.n_robots, dtype=np.int64)
        first = floor.reading()
        if self.rows(np.asarray(first.ids, dtype=np.int64)).shape != self.fleet_ids.shape:
            raise ValueError(f"region {region.name}: robots {self.fleet_ids.tolist()} are not all on the floor")
        self._t0 = first.time
        self._closed = False
        #: the job's script drives these robots now (after the set-up, until the return): the floor stops the region
        #: when the others wait more than ``stall_s`` for its commands (:meth:`SharedFloor._stop_stalled`)
        self.watched = False

    def rows(self, floor_ids: NDArray[np.int64]) -> NDArray[np.intp]:
        """Rows of the job's robots in a floor reading with ids ``floor_ids`` (job order; missing ones left out)."""
        rows, present = rows_of(floor_ids, self.fleet_ids)
        return np.asarray(rows, dtype=np.intp)[present]

    # ---------------------------------------------------------------- pose source
    def read(self, now: float = 0.0) -> SensedPoses:
        full = self.floor.reading()
        r = self.rows(np.asarray(full.ids, dtype=np.int64))
        poses = self.region.to_local(np.asarray(full.poses, dtype=float)[r])

        def pick(values: Any) -> Any:
            return None if values is None else np.asarray(values)[r].copy()

        t = None if full.time is None or self._t0 is None else float(full.time) - float(self._t0)
        return SensedPoses(self._ids.copy(), poses, np.asarray(full.seen, dtype=bool)[r].copy(),
                           is_virtual=pick(full.is_virtual), battery=pick(full.battery),
                           charging=pick(full.charging), time=t)

    @property
    def bounds(self) -> Any:
        """The region as the job sees it (centred on its origin), m."""
        return self.region.local_bounds

    def health(self) -> str:
        return "emergency stop" if self.floor.stopped(self.region.name) else "ok"

    # ---------------------------------------------------------------- command sink
    def send(self, ids: NDArray[np.int64], v: NDArray[np.float64], w: NDArray[np.float64]) -> None:
        if len(ids) != self.n_robots or np.any(np.asarray(ids) != self._ids):
            raise ValueError(f"the job's robots are 0..{self.n_robots - 1}, in order")
        v = np.asarray(v, dtype=float).reshape(self.n_robots)
        w = np.asarray(w, dtype=float).reshape(self.n_robots)
        ok = np.isfinite(v) & np.isfinite(w)
        self.floor._submit(self.region.name, np.where(ok, v, 0.0), np.where(ok, w, 0.0))

    def hold(self) -> None:
        """One period standing still."""
        self.floor._submit(self.region.name, np.zeros(self.n_robots), np.zeros(self.n_robots))

    def obstacles(self) -> FloatArray:
        """``(K, 2)`` look-ahead points of every other robot on the floor, in the region's frame, m."""
        full = self.floor.reading()
        others = ~np.isin(np.asarray(full.ids, dtype=np.int64), self.fleet_ids)
        points = lookahead_points(np.asarray(full.poses, dtype=float)[others], self.floor.params.lookahead)
        return self.region.to_local(points[np.all(np.isfinite(points), axis=1)])

    def close(self) -> None:
        """One period of zero commands (as :class:`~swarmdeck.devices.fleet.assigned.AssignedRobots` closes); the
        region stays open (its robots are returned next, then :meth:`leave`)."""
        if not self._closed:
            try:
                self.hold()
            except FloorClosed:
                pass

    def leave(self) -> None:
        """The job is over: the region leaves the floor's ticks (its robots stand still). Idempotent."""
        if not self._closed:
            self._closed = True
            self.floor._leave(self.region.name)


def simulated_floor(layout: RegionLayout, per_region: int | dict[str, int], *, params: GritsBotParams | None = None,
                    dt: float = CONTROL_PERIOD, spacing: float = PARKING_SPACING) -> SharedFloor:
    """A :class:`SharedFloor` over simulated robots parked in every region: ``per_region`` robots (one count, or
    one per region name; a nested layout's leaves only: :attr:`RegionLayout.leaves`) on a lattice of pitch ``spacing``
    m inside each region (D_s from its edges), heading +x,
    the sites nearest the region's floor walls first; floor ids region by region in layout order. ValueError naming
    the region that cannot hold its count."""
    parts = []
    leaves = set(layout.leaves)  # a nested layout parks its robots in its leaves only
    for r in layout.regions:  # a handful of regions, once
        if r.name not in leaves:
            continue
        n = per_region if isinstance(per_region, int) else int(per_region.get(r.name, 0))
        sites = lattice_sites(r.bounds, spacing, SAFETY_DISTANCE)
        if len(sites) < n:
            raise ValueError(f"region {r.name}: it holds {len(sites)} parked robots {spacing} m apart, not {n}")
        f = layout.floor
        to_wall = np.minimum.reduce([sites[:, 0] - f.x_min, f.x_max - sites[:, 0], sites[:, 1] - f.y_min,
                                     f.y_max - sites[:, 1]])
        parts.append(np.column_stack([sites[np.argsort(to_wall, kind="stable")[:n]], np.zeros(n)]))
    poses = np.vstack(parts)
    robots = SimulatedRobots(len(poses), ArenaConfig(bounds=layout.floor, dt=dt), params, initial_poses=poses)
    return SharedFloor(robots, layout, params=params, dt=dt)
