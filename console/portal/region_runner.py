"""The portal's arena divided into regions: one job per region at once on one shared floor (issue 30.1).

:class:`RegionRunner` stands where :class:`~.runner.ArenaRunner` stands (``service.arena``; ``swarmdeck server
--regions LAYOUT``): it owns one :class:`~swarmdeck.devices.fleet.floor.SharedFloor` (simulated robots parked in
every region; one barrier over every robot, each job's robots held in their region by wall rows) and one *lane*
per region — an :class:`~.runner.ArenaRunner` whose fleet is that region (:class:`RegionFleet`) and whose arena is
the region as its job sees it (``ArenaSettings.bounds`` = the region's local bounds). Each lane claims the first
job of the queue that its region holds, so up to one job per region runs at once; each job has its own recording,
``run.json``, exports and result exactly as on a whole arena, the script sees its region as its arena, its robots
are set up and returned inside the region.

An operator's emergency stop (``POST /api/operator/estop``) stops every region and the floor; :meth:`estop_region`
stops one region's job and robots (the others run on). Live frames of every running job go to the one LiveFeed
(tagged with their job).
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.console.portal.exports import JobExports
from swarmdeck.console.portal.livefeed import LiveFeed
from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.portal.service import PortalService
from swarmdeck.console.runtime.fleet_upkeep import UpkeepResult
from swarmdeck.console.runtime.region_jobs import UPKEEP_LIMIT_S, drive_to, region_start_poses
from swarmdeck.core.bounds import Bounds
from swarmdeck.core.ports import rows_of
from swarmdeck.devices.fleet.floor import FloorClosed, RegionRobots, SharedFloor, simulated_floor
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
        return result, (view if report["ok"] else None)

    def end_assignment(self) -> None:
        """The job is over (its robots return next)."""

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


class RegionRunner:
    """Several jobs at once, one per region of one floor (module docstring). ``per_region``: simulated robots
    parked in each region (one count or one per region)."""

    def __init__(self, service: PortalService, settings: ArenaSettings, layout: RegionLayout,
                 per_region: int | dict[str, int], live: LiveFeed | None = None, *, poll_s: float = 1.0) -> None:
        if settings.robots_via is not None:
            raise ValueError("regions run on the simulated floor for now (no --robots-via)")
        self.service, self.layout, self.settings = service, layout, settings
        self.floor = simulated_floor(layout, per_region, dt=settings.dt)
        self.live = live if live is not None else LiveFeed()
        cap = {k: min(v, len(self.floor.free_robots(k))) for k, v in layout.capacity().items()}
        self.lanes: dict[str, ArenaRunner] = {}
        for r in layout.regions:
            fleet = RegionFleet(self.floor, r.name, settings.seed)
            self.lanes[r.name] = ArenaRunner(service, replace(settings, bounds=r.local_bounds, fleet=cap[r.name]),
                                             self.live, poll_s=poll_s, fleet=fleet)
        self.frame_listeners: list[Callable[[Any], None]] = []
        for lane in self.lanes.values():
            lane.frame_listeners = self.frame_listeners
            lane.fleet.frame_listeners = self.frame_listeners

    @property
    def exports(self) -> JobExports:
        """The first region's exports process (the portal resumes unfinished exports through it at start)."""
        return next(iter(self.lanes.values())).exports

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
        """Every region: the floor stops at once and every job ends."""
        self.floor.estop()
        for lane in self.lanes.values():
            lane.emergency_stop()

    def estop_region(self, name: str) -> int | None:
        """Stop region ``name``'s robots and end its job (the other regions run on); the job's id, or None."""
        lane = self.lanes[self.layout.region(name).name]
        job = lane.current_job
        self.floor.estop(name)
        with lane._lock:
            loop = lane._loop
            if lane._job is not None:
                lane._end_job.set()
        if loop is not None:
            loop.estop()
        return job

    def cancel(self, job_id: int) -> None:
        for lane in self.lanes.values():
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
