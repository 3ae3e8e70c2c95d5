"""The portal's arena divided into regions: one job per region at once on one shared floor (issue 30.1).

:class:`RegionRunner` stands where :class:`~.runner.ArenaRunner` stands (``service.arena``; ``swarmdeck server
--regions LAYOUT``): it owns one :class:`~swarmdeck.devices.fleet.floor.SharedFloor` (simulated robots parked in
every region; one barrier over every robot, each job's robots held in their region by wall rows) and one *lane*
per region — an :class:`~.runner.ArenaRunner` whose fleet is that region (:class:`RegionFleet`) and whose arena is
the region as its job sees it (``ArenaSettings.bounds`` = the region's local bounds). Each lane claims the first
job of the queue that its region holds, so up to one job per region runs at once; each job has its own recording,
``run.json``, exports and result exactly as on a whole arena, the script sees its region as its arena, its robots
are set up and returned inside the region.

The queue sees the divided floor as one arena with one *slot* per region (:func:`region_arena`: the
:class:`~.arenas.ArenaSpec`'s ``slot_names`` and ``slot_robots``, from ``--arena NAME=sim,regions=2x2`` or
``--regions``): the plan places each job on a region that holds its robots, ETAs and fair share are the plan's as on
any arena, and the lane of region R claims with ``claim_for_arena(arena=NAME, slot=R)`` (the job's ``placed`` is
``NAME/R``).

An operator's emergency stop (``POST /api/operator/estop``) stops every region and the floor; one region's
(:meth:`~.service.PortalService.emergency_stop_region`, ``POST /api/operator/arenas/NAME/regions/R/estop``) stops that
region's robots and ends its job (the floor's barrier keeps the other regions' robots running; :meth:`estop_region`)
and latches the region until released. Live frames of every running job go to the one LiveFeed (tagged with their
job: each job's live view shows its region's robots only, in its region's frame).
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.console.portal.arenas import ArenaSpec
from swarmdeck.console.portal.exports import JobExports
from swarmdeck.console.portal.livefeed import LiveFeed
from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.portal.service import PortalService
from swarmdeck.console.runtime.fleet_upkeep import UpkeepResult
from swarmdeck.console.runtime.region_jobs import UPKEEP_LIMIT_S, drive_to, region_start_poses
from swarmdeck.core.bounds import Bounds
from swarmdeck.core.ports import rows_of
from swarmdeck.devices.fleet.floor import STALL_LIMIT_S, FloorClosed, RegionRobots, SharedFloor, simulated_floor
from swarmdeck.devices.fleet.regions import RegionLayout


class RegionFleet:
    """Region ``name`` of ``floor`` as an arena runner's fleet: the robots standing in it, set up and returned
    inside it (the interface :class:`~.arena_fleet.ArenaFleet` offers the runner)."""

    def __init__(self, floor: SharedFloor, name: str, seed: int | None = None) -> None:
        self.floor, self.name = floor, name
        self.region = floor.layout.region(name)
        self.seed = seed
        self.frame_listeners: list[Callable[[Any], None]] = []
        self._view: RegionRobots | None = None
        self._parked: NDArray[np.float64] | None = None
        self._starts = 0

    @property
    def bounds(self) -> Bounds:
        """The region as its jobs see it, m."""
        return self.region.local_bounds

    def shortfall(self, n: int) -> str | None:
        """None when ``n`` robots of the region are free; else why the job waits."""
        free = len(self.floor.free_robots(self.name)) if self._view is None else 0
        return None if free >= int(n) else f"region {self.name}: {free} free robot(s), the job needs {int(n)}"

    def start_poses(self, n: int) -> NDArray[np.float64]:
        """``(n, 3)`` random valid start poses for the region's next ``n`` robots (region frame,
        :func:`~swarmdeck.console.runtime.region_jobs.region_start_poses`; where they stand when it is crowded)."""
        self._starts += 1
        seed = None if self.seed is None else self.seed + self._starts
        chosen = self.floor.free_robots(self.name)[:int(n)]
        poses = region_start_poses(self.floor, self.name, chosen, seed)
        if poses is None:
            reading = self.floor.reading()
            rows, _ = rows_of(reading.ids, chosen)
            poses = self.region.to_local(np.asarray(reading.poses, dtype=float)[rows])
        return poses

    def set_up(self, job_id: int, goals: ArrayLike, *, stop: Callable[[], bool], on_loop: Any
               ) -> tuple[UpkeepResult, RegionRobots | None]:
        """Open the region with ``len(goals)`` of its robots and drive them to ``goals`` (region frame)."""
        goals_arr = np.asarray(goals, dtype=float).reshape(-1, 3)
        view = self.floor.open_region(self.name, len(goals_arr), goals=goals_arr)
        self._view, self._parked = view, view.read().poses.copy()
        report = drive_to(view, goals_arr, UPKEEP_LIMIT_S, stop)
        result = _result(report, view.fleet_ids, "set up in region " + self.name)
        view.watched = bool(report["ok"])  # the script drives them now: a stall stops the region
        return result, (view if report["ok"] else None)

    def end_assignment(self) -> None:
        """The job is over (its robots return next, the runner's own maneuver: no longer watched for stalls)."""
        if self._view is not None:
            self._view.watched = False

    def away(self) -> bool:
        """The region still holds a job's robots off their parking places (after a stop)."""
        return self._view is not None

    def return_all(self, *, stop: Callable[[], bool], on_loop: Any) -> UpkeepResult:
        """The job's robots back to where they were parked; the region is free again."""
        view, parked = self._view, self._parked
        if view is None or parked is None:
            return UpkeepResult(True, (), 0.0, math.nan, math.nan, 0, 0, "nothing to return")
        self.floor.release(self.name)
        try:
            report = drive_to(view, parked, UPKEEP_LIMIT_S, stop)
        except FloorClosed as exc:
            return UpkeepResult(False, (), 0.0, math.nan, math.nan, 0, 0, str(exc))
        if report["ok"]:
            view.leave()
            self._view = self._parked = None
        return _result(report, view.fleet_ids, "returned in region " + self.name)

    def idle(self, seconds: float) -> None:
        """Parked simulated robots need no charging here."""

    def status(self) -> dict[str, Any]:
        return {"region": self.name, "bounds": list(self.region.bounds),
                "job_robots": [] if self._view is None else self._view.fleet_ids.tolist(),
                "free_robots": self.floor.free_robots(self.name).tolist()}

    def close(self) -> None:
        if self._view is not None:
            self._view.leave()
            self._view = None


def _result(report: dict[str, Any], fleet_ids: NDArray[np.int64], what: str) -> UpkeepResult:
    missing = report.get("robots", [])
    message = f"{what}: {'done' if report['ok'] else 'robots ' + str(missing) + ' did not arrive'}"
    return UpkeepResult(bool(report["ok"]), tuple(int(i) for i in fleet_ids), float(report["seconds"]), math.nan,
                        math.nan, 0, 0, message)


def share_robots(layout: RegionLayout, robots: int) -> dict[str, int]:
    """``robots`` parked robots shared out between the layout's regions — a nested layout's leaves
    (:attr:`RegionLayout.leaves`) — in layout order; the first regions get one more when it does not divide."""
    names = layout.leaves
    return {name: robots // len(names) + (1 if k < robots % len(names) else 0) for k, name in enumerate(names)}


def region_arena(spec: ArenaSpec, layout: RegionLayout, per_region: int | dict[str, int] | None = None) -> ArenaSpec:
    """``spec`` as the plan sees a floor divided by ``layout``: one slot per region (its name), each holding the
    robots parked there (``per_region``; None: ``spec.robots`` shared out, :func:`share_robots`) up to the region's
    capacity (:meth:`RegionLayout.capacity`). ValueError when a region would hold no robot."""
    share = share_robots(layout, spec.robots) if per_region is None else (
        per_region if isinstance(per_region, dict) else {n: int(per_region) for n in layout.leaves})
    cap = layout.capacity()
    parked = {n: sum(int(share.get(leaf, 0)) for leaf in (n, *layout.conflicts(n)) if leaf in layout.leaves)
              for n in layout.names}  # a nested layout's region: the robots parked in the leaves inside it
    held = tuple(min(parked[n], int(cap[n])) for n in layout.names)
    empty = [n for n, k in zip(layout.names, held) if k < 1]
    if empty:
        raise ValueError(f"regions {', '.join(empty)} would hold no robot: give the arena more robots "
                         f"({spec.robots} for {len(layout.names)} regions)")
    return replace(spec, slots=len(layout.names), slot_names=tuple(layout.names), slot_robots=held,
                   slot_bounds=tuple(r.local_bounds for r in layout.regions),
                   slot_conflicts=tuple(tuple(layout.names.index(c) for c in layout.conflicts(n))
                                        for n in layout.names),
                   robots=sum(int(share.get(n, 0)) for n in layout.leaves))


class RegionRunner:
    """Several jobs at once, one per region of one floor (module docstring). ``per_region``: simulated robots
    parked in each region (one count or one per region). ``stall_s``: wall s the other regions wait for one region's
    commands before that region is stopped and its job failed as stalled (:data:`~swarmdeck.devices.fleet.floor.
    STALL_LIMIT_S`; :meth:`_stalled`)."""

    def __init__(self, service: PortalService, settings: ArenaSettings, layout: RegionLayout,
                 per_region: int | dict[str, int], live: LiveFeed | None = None, *, poll_s: float = 1.0,
                 exports: JobExports | None = None, stall_s: float = STALL_LIMIT_S) -> None:
        if settings.robots_via is not None:
            raise ValueError("regions run on the simulated floor for now (no --robots-via)")
        name = settings.name or service.config.arena_specs()[0].name
        spec = next((a for a in service.config.arena_specs() if a.name == name), None)
        if spec is None or spec.slot_names != tuple(layout.names):
            raise ValueError(f"the portal's arena {name!r} is not planned as these regions: give PortalConfig.arenas "
                             f"region_arena(ArenaSpec({name!r}, ...), layout) (swarmdeck server does)")
        settings = replace(settings, name=name)
        self.name = name
        self.service, self.layout, self.settings = service, layout, settings
        self.floor = simulated_floor(layout, per_region, dt=settings.dt)
        self.floor.stall_s, self.floor.on_stall = float(stall_s), self._stalled
        self.live = live if live is not None else LiveFeed()
        cap = {k: min(v, len(self.floor.free_robots(k))) for k, v in layout.capacity().items()}
        # one exports process for the floor (not one per region): the ended jobs' CSV, replay and video in turn
        self._exports = exports if exports is not None else JobExports(service)
        self.lanes: dict[str, ArenaRunner] = {}
        for k, r in enumerate(layout.regions):
            fleet = RegionFleet(self.floor, r.name, settings.seed)
            self.lanes[r.name] = ArenaRunner(service, replace(settings, bounds=r.local_bounds, fleet=cap[r.name],
                                                              slot=k), self.live, poll_s=poll_s, fleet=fleet,
                                             exports=self._exports)
        self.frame_listeners: list[Callable[[Any], None]] = []
        for lane in self.lanes.values():
            lane.frame_listeners = self.frame_listeners
            lane.fleet.frame_listeners = self.frame_listeners

    @property
    def exports(self) -> JobExports:
        """The floor's exports process, shared by its regions (the portal resumes unfinished exports through it)."""
        return self._exports

    # ------------------------------------------------------------------ what the service asks
    def start(self) -> RegionRunner:
        for lane in self.lanes.values():
            lane.start()
        return self

    def stop(self, timeout: float = 15.0) -> None:
        for lane in self.lanes.values():
            lane._stop.set()
            lane._end_job.set()
            lane._halt.set()
        self.floor.close()
        for lane in self.lanes.values():
            lane.stop(timeout)

    def recover(self) -> list[int]:
        """Jobs the previous server left on the arena: interrupted, partial recordings recovered."""
        return next(iter(self.lanes.values())).recover()

    def emergency_stop(self) -> None:
        """Every region: the floor stops at once and every job ends (each region is released by its next return)."""
        for name in self.layout.names:
            self.floor.estop(name)
        for lane in self.lanes.values():
            lane.emergency_stop()

    def estop_region(self, name: str) -> int | None:
        """Stop region ``name``'s robots and end its job (the other regions run on); the job's id, or None. On a
        floor of regions allocated per job (nested), a job running on a region around it or inside it is stopped
        too (its robots stand in the stopped region)."""
        lane = self.lanes[self.layout.region(name).name]
        job = lane.current_job
        for other in self.layout.conflicts(name):  # nested regions: a handful
            if self.lanes[other].current_job is not None:
                self._stop_lane(other)
        self._stop_lane(name)
        return job

    def _stop_lane(self, name: str) -> None:
        lane = self.lanes[name]
        self.floor.estop(name)
        with lane._lock:
            loop = lane._loop
            if lane._job is not None:
                lane._end_job.set()
        if loop is not None:
            loop.estop()

    def _stalled(self, name: str, why: str) -> None:
        """The floor stopped region ``name`` as stalled (its job sent no commands while the others waited): its job
        fails with ``why`` (counted in ``floor.stats.stalled``); its robots return, the region takes the next job."""
        self.lanes[name].fail_job(why)

    def cancel(self, job_id: int) -> None:
        """End job ``job_id`` (its owner or an operator cancelled it): its region's robots stop at the next tick (the
        others run on), then return to their parking places; the region takes the next job."""
        for name, lane in self.lanes.items():
            if lane.current_job == int(job_id):
                self.floor.estop(name)
            lane.cancel(job_id)

    @property
    def current_jobs(self) -> dict[str, int | None]:
        """``{region: the job running there (or None)}``."""
        return {name: lane.current_job for name, lane in self.lanes.items()}

    @property
    def current_job(self) -> int | None:
        jobs = [j for j in self.current_jobs.values() if j is not None]
        return jobs[0] if jobs else None

    def live_log(self, job_id: int) -> bytes | None:
        for lane in self.lanes.values():
            log = lane.live_log(job_id)
            if log is not None:
                return log
        return None

    def alerts(self) -> dict[str, Any]:
        messages: list[str] = []
        for lane in self.lanes.values():
            messages.extend(lane.alerts()["messages"])
        return {"job": self.current_job, "messages": messages[-50:]}

    def fleet_status(self) -> dict[str, Any]:
        return {"regions": {name: lane.fleet_status() for name, lane in self.lanes.items()},
                "floor": self.floor.stats.to_dict(), "capacity": self.layout.capacity()}
