"""Run an unmodified experiment script in one region of a shared floor: set up, run, return (issue 30.1).

:func:`run_in_region` is what a runner does for each region's job, on its own thread (one per region; the
floor's ticks are lockstep, :mod:`swarmdeck.devices.fleet.floor`):

1. when the script builds its Arena (or rps Robotarium) with N robots, region ``name`` is opened with N of
   the robots standing in it (:meth:`SharedFloor.open_region`), and they are **set up** at the script's
   initial conditions (region-local), else at ``start_poses`` (``"parked"``: where they stand), else at random
   valid poses inside the
   region's start area — driven there through the floor's one barrier (:func:`drive_to`);
2. the script runs on the region's ports (:class:`~swarmdeck.devices.fleet.floor.RegionRobots`) with the
   region as its arena (``run_experiment(..., bounds=region.local_bounds)``): its own bounds, origin and
   robot ids; :func:`~swarmdeck.devices.runner.run_experiment` gives the same result as a solo run;
3. its robots **return** to where they stood before the set-up, and the region is closed — also when the
   script failed or the region was stopped (then they stay where they stopped).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.bounds import Bounds
from swarmdeck.core.kinematics import si_to_unicycle
from swarmdeck.core.ports import rows_of
from swarmdeck.devices.controllers import HybridPoseController, at_pose
from swarmdeck.devices.fleet.floor import FloorClosed, RegionRobots, SharedFloor
from swarmdeck.devices.fleet.regions import Region
from swarmdeck.devices.initial_conditions import random_initial_poses
from swarmdeck.devices.runner import RunResult, run_experiment

FloatArray = NDArray[np.float64]

#: s a region's set-up or return may take before it is given up (the robots then stop where they are)
UPKEEP_LIMIT_S = 60.0
#: a robot that moved less than STUCK_DISTANCE m in STUCK_S s on its way is deadlocked: it sidesteps for ESCAPE_S s
#: at ESCAPE_SPEED m/s (the barrier keeps the sidestep safe)
STUCK_DISTANCE, STUCK_S, ESCAPE_S, ESCAPE_SPEED = 0.01, 3.0, 1.0, 0.1
#: m around the chosen robots where a job's random start poses are drawn first (:func:`region_start_poses`)
NEAR_M = 0.25


@dataclass
class RegionJobResult:
    """What :func:`run_in_region` did: the region, the floor ids of the job's robots, the script's
    :class:`~swarmdeck.devices.runner.RunResult` (as a solo run's), the set-up and return (``ok``, ``seconds`` of
    floor time, ``robots`` not there), why the job could not run (``error``) and, from :func:`run_queue`, the floor
    time it was taken from the queue and ended at (``started_s``, ``ended_s``, s; None otherwise)."""

    region: str
    fleet_ids: list[int] = field(default_factory=list)
    run: RunResult | None = None
    setup: dict[str, Any] = field(default_factory=dict)
    returned: dict[str, Any] = field(default_factory=dict)
    error: str | None = None
    started_s: float | None = None
    ended_s: float | None = None


def drive_to(view: RegionRobots, goals: ArrayLike, limit_s: float = UPKEEP_LIMIT_S,
             stop: Callable[[], bool] | None = None) -> dict[str, Any]:
    """Drive the region's robots to ``goals`` ``(N, 3)`` (region frame, m/rad) through the floor's barrier;
    ``{"ok", "seconds", "robots", "escapes"}`` (robots not at their goal when it ended: the time limit, ``stop`` or a
    stopped region). A robot that made no progress for :data:`STUCK_S` (a deadlock of the barrier) sidesteps for
    :data:`ESCAPE_S` (its way to the goal turned by 90°), then goes on."""
    goals = np.asarray(goals, dtype=float).reshape(view.n_robots, 3)
    ctrl = HybridPoseController()
    dt = view.floor.dt
    ticks, limit = 0, int(np.ceil(limit_s / dt))
    ids = np.arange(view.n_robots, dtype=np.int64)
    poses = view.read().poses
    stuck_ticks, escape_ticks = int(round(STUCK_S / dt)), int(round(ESCAPE_S / dt))
    anchor, since = poses[:, :2].copy(), np.zeros(view.n_robots, dtype=np.int64)
    escaping = np.zeros(view.n_robots, dtype=np.int64)  # ticks of sidestep left
    escapes = 0
    while not np.all(arrived := at_pose(poses, goals)) and ticks < limit:
        if (stop is not None and stop()) or view.floor.stopped(view.region.name):
            break
        v, w = ctrl(poses, goals)
        moved = np.linalg.norm(poses[:, :2] - anchor, axis=1) > STUCK_DISTANCE
        anchor[moved], since[moved] = poses[moved, :2], 0
        since[~moved] += 1
        start = (since >= stuck_ticks) & ~arrived & (escaping == 0)
        escaping[start], since[start] = escape_ticks, 0
        escapes += int(start.sum())
        side = escaping > 0
        if side.any():  # sidestep: the way to the goal turned by +90°, at a walking pace
            to_goal = goals[side, :2] - poses[side, :2]
            norm = np.maximum(np.linalg.norm(to_goal, axis=1, keepdims=True), 1e-9)
            u = np.column_stack([-to_goal[:, 1], to_goal[:, 0]]) / norm * ESCAPE_SPEED
            v[side], w[side] = si_to_unicycle(poses[side], u, view.floor.params.lookahead)
            escaping[side] -= 1
        view.send(ids, v, w)
        ticks += 1
        poses = view.read().poses
    missing = np.flatnonzero(~at_pose(poses, goals))
    return {"ok": not len(missing), "seconds": round(ticks * dt, 3), "robots": missing.tolist(), "escapes": escapes}


def region_start_poses(floor: SharedFloor, name: str, chosen: ArrayLike, seed: int | None = None) -> FloatArray | None:
    """Random valid start poses ``(N, 3)`` (region frame) for the floor robots ``chosen`` of region ``name``: inside
    the region's start area, clear of the region's other robots, and first near where the chosen robots stand (their
    box grown by :data:`NEAR_M`: short ways that cross no parked robot); None when the region is too crowded (then
    the job starts where its robots stand)."""
    region = floor.layout.region(name)
    chosen = np.asarray(chosen, dtype=np.int64)
    reading = floor.reading()
    rows, _ = rows_of(reading.ids, chosen)
    here = region.to_local(np.asarray(reading.poses, dtype=float)[rows, :2])
    a, (ox, oy) = floor.layout.start_area(name), region.origin
    area = Bounds(a.x_min - ox, a.x_max - ox, a.y_min - oy, a.y_max - oy)
    lo, hi = here.min(axis=0) - NEAR_M, here.max(axis=0) + NEAR_M
    near = Bounds(max(area.x_min, lo[0]), min(area.x_max, hi[0]), max(area.y_min, lo[1]), min(area.y_max, hi[1]))
    avoid = _staying(floor, region, chosen)
    for box in (near, area):
        if box.width <= 0 or box.height <= 0:
            continue
        try:
            return random_initial_poses(len(chosen), box, rng=seed, avoid=avoid)
        except ValueError:  # more robots than fit there
            continue
    return None


def _staying(floor: SharedFloor, region: Region, chosen: NDArray[np.int64]) -> FloatArray:
    """``(K, 2)`` region-frame positions of the floor's robots standing in ``region`` other than ``chosen`` (the
    job's start poses avoid them)."""
    full = floor.reading()
    xy = np.asarray(full.poses, dtype=float)[:, :2]
    others = ~np.isin(np.asarray(full.ids, dtype=np.int64), chosen) & region.bounds.contains(xy)
    return region.to_local(xy[others])


def run_in_region(floor: SharedFloor, name: str, target: str | Path | Callable[..., Any], *,
                  n_robots: int | None = None, duration: float | None = None, seed: int | None = None,
                  start_poses: ArrayLike | None = None, argv: tuple[str, ...] = (),
                  upkeep_limit_s: float = UPKEEP_LIMIT_S,
                  on_start: Callable[[RegionRobots], None] | None = None) -> RegionJobResult:
    """Run ``target`` (a script file or an ``experiment(arena)`` callable, unmodified) in region ``name`` of
    ``floor`` (module docstring). ``on_start(view)`` is called once the robots are set up, before the script's
    first step (e.g. to mark the job running). Never raises for the script's own failures (they are in
    ``result.run``)."""
    region = floor.layout.region(name)
    result = RegionJobResult(region=name)
    held: dict[str, Any] = {}

    def robots(n: int, initial: Any, config: Any = None, params: Any = None) -> RegionRobots:
        if "view" in held:
            raise ValueError(f"region {name}: the job already has its robots (one Arena per job)")
        free = floor.free_robots(name)
        if len(free) < int(n):
            raise ValueError(f"region {name} has {len(free)} free robot(s), the job asks for {int(n)}")
        chosen = free[:int(n)]
        goals: FloatArray | None = None
        if initial is not None:
            goals = np.asarray(initial, dtype=float).reshape(int(n), 3)
        elif isinstance(start_poses, str):
            if start_poses != "parked":
                raise ValueError(f"start_poses must be poses or 'parked', got {start_poses!r}")
        elif start_poses is not None:
            goals = np.asarray(start_poses, dtype=float).reshape(int(n), 3)
        else:
            goals = region_start_poses(floor, name, chosen, seed)
        view = floor.open_region(name, chosen, goals=goals)
        held["view"] = view
        result.fleet_ids = view.fleet_ids.tolist()
        held["parked"] = view.read().poses.copy()
        result.setup = drive_to(view, held["parked"] if goals is None else goals, upkeep_limit_s)
        if not result.setup["ok"]:
            raise ValueError(f"region {name}: set-up failed, robots {result.setup['robots']} did not reach their "
                             "start poses")
        view.watched = True  # the script drives them now: a stall stops the region (SharedFloor.stall_s)
        if on_start is not None:
            on_start(view)
        return view

    try:
        result.run = run_experiment(target, n_robots=n_robots, duration=duration, seed=seed, backend_factory=robots,
                                    bounds=region.local_bounds, argv=argv)
    except (ValueError, FloorClosed) as exc:
        result.error = str(exc)
    finally:
        view = held.get("view")
        if view is not None:
            view.watched = False
            try:
                if not floor.stopped(name):
                    result.returned = drive_to(view, held["parked"], upkeep_limit_s)
            except FloorClosed as exc:
                result.returned = {"ok": False, "message": str(exc)}
            finally:
                view.leave()
    return result


@dataclass(frozen=True)
class QueuedJob:
    """A job of a queue on a shared floor: ``target`` (script file or ``experiment(arena)`` callable), its robots
    and declared duration (s), and a ``name`` for the report."""

    name: str
    target: Any
    robots: int
    duration: float
    seed: int | None = None
    start_poses: Any = None  # run_in_region's: None (random valid ones), "parked" or (N, 3) poses


def run_queue(floor: SharedFloor, jobs: list[QueuedJob], *, regions: tuple[str, ...] | None = None,
              upkeep_limit_s: float = UPKEEP_LIMIT_S) -> list[tuple[QueuedJob, RegionJobResult]]:
    """Run ``jobs`` in queue order, one per region at a time, every region busy while jobs wait (one worker
    thread per region; a job goes to the first free region that holds it, :meth:`RegionLayout.capacity`).
    ``regions``: the regions to use (default: all; a nested layout's leaves — regions allocated per job are the
    portal's plan, :class:`~swarmdeck.console.portal.region_runner.RegionRunner`). Returns ``(job, result)`` in the
    order the jobs ended.
    ValueError before anything moves when a job fits no region (:meth:`RegionLayout.never_fits`)."""
    import functools
    import threading

    from swarmdeck.core.service_thread import ServiceThread

    names = regions if regions is not None else (floor.layout.leaves if floor.layout.nested else floor.layout.names)
    cap = floor.layout.capacity()
    for job in jobs:
        if not any(cap[n] >= job.robots for n in names):
            raise ValueError(f"job {job.name}: {floor.layout.never_fits(job.robots) or 'fits none of ' + str(names)}")
    lock = threading.Lock()
    waiting = list(jobs)
    done: list[tuple[QueuedJob, RegionJobResult]] = []

    def worker(region: str) -> None:
        while True:
            with lock:
                job = next((j for j in waiting if j.robots <= cap[region]), None)
                if job is None:
                    return
                waiting.remove(job)
            started = _floor_time(floor)
            result = run_in_region(floor, region, job.target, n_robots=job.robots, duration=job.duration,
                                   seed=job.seed, upkeep_limit_s=upkeep_limit_s, start_poses=job.start_poses)
            result.started_s, result.ended_s = started, _floor_time(floor)
            with lock:
                done.append((job, result))

    threads = [ServiceThread(functools.partial(worker, n), f"swarmdeck-region-{n}", join_timeout=None) for n in names]
    for t in threads:
        t.start()
    for t in threads:
        t.stop()  # joins: each worker ends when no waiting job fits its region
    return done


def _floor_time(floor: SharedFloor) -> float | None:
    """The floor's clock now, s (its robots' reading; None when they keep no time)."""
    t = floor.reading().time
    return None if t is None else float(t)
