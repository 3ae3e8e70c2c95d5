"""The arena runner: one job at a time on the arena, through the console's runtime, the user's code in the sandbox.

For each job the service hands over (``in arena queue → setting up``):

1. **Robots** (:class:`~.arena_fleet.ArenaFleet`, the arena's one fleet of
   ``ArenaSettings.fleet`` = M robots, simulated or the MQTT fleet's ids 0…M−1, docked on
   the chargers): a job is claimed only when N charged, healthy robots can be
   assigned — otherwise it stays ``in arena queue`` and its ``reason`` says which robots
   are not ready and why (they charge on the strips; the job starts when they
   are). The assigned robots are set up at the job's start poses (the manifest's,
   else the script's initial conditions, else random valid ones:
   :func:`~swarmdeck.console.sandbox.start_poses.arena_start`, the rule verification
   uses too) under the barrier; the job then runs on them as robots 0…N−1
   (:class:`~swarmdeck.devices.fleet.assigned.AssignedRobots`), the
   docked robots fixed obstacles of its barrier. A set-up that fails (time limit,
   lost robot, a start pose on a docked robot) stops the robots and fails the job
   naming them.
2. **Runtime**: a :class:`~swarmdeck.console.runtime.loop.ControlLoop` — the
   same tick pipeline, safety filter (``devices.pipeline.certify``) and
   recorder as ``swarmdeck console`` — whose behaviour is
   :class:`SandboxCommands`: the script's nominal look-ahead velocities of this
   tick, as the sandbox hands them over, which the loop certifies (so without
   the barrier and within the limits the robots get the script's commands
   unchanged). The barrier is off only when
   :meth:`~.service.PortalService.bypass_allowed` said so at claim time (an operator
   approved that job's bypass), and then the loop's **guard** (``ArenaSettings.guard``,
   :mod:`swarmdeck.safety.guard`) keeps the walls and docked robots hard and switches the
   barrier back on for the rest of the run the first time a pair would come closer than
   the guard distance or the barrier would intervene by more than its threshold. Contacts
   between robots are detected on every run. Both are events in the recording, alerts on
   the operator page (:meth:`ArenaRunner.alerts`) and part of the result: ``run.json``'s
   ``bypass`` (granted, revoked: when and why) and ``contacts`` (count, robots, episodes),
   and the job's reason.
3. **Script**: :func:`swarmdeck.console.sandbox.run.run_sandboxed` with
   :meth:`SandboxPlant.on_loop <swarmdeck.console.sandbox.plant.SandboxPlant.on_loop>` as its plant: each sandbox tick is one loop tick, paced
   in real time (MQTT robots always; the simulated arena unless ``fast``). On the
   real-time arena the script's commands for a tick are due within
   :meth:`~.service.PortalConfig.arena_budget` (one control period, 33 ms, by
   default): a late tick stops the robots for that tick, 1 s of late ticks in a
   row ends the run (``overruns``). The
   time limit is the declared duration plus ``grace_s`` plus the set-up's own
   time limit (the script waits while its robots are set up); a cancel or an
   emergency stop ends the run within a tick (the e-stop zeroes the robots'
   commands first).
4. **Data** in ``DIR/jobs/<id>/``: ``recording.mcap`` (written while it runs),
   ``script.log``, ``run.json`` (how it ended); then the exports (``robots.csv``,
   ``frames.csv``, ``replay.html``, ``video.mp4``) are handed to
   :attr:`ArenaRunner.exports` (:class:`~.exports.JobExports`, a child process) and
   the next job starts at once; the job's ``exports`` field says when they are
   ready. An emergency stop is in the recording: the stopped tick (zero commands,
   ``run_state`` "estop", the event "EMERGENCY STOP") is recorded before the
   loop closes. Every Frame is also
   published to the :class:`~.livefeed.LiveFeed` and handed to each of
   :attr:`ArenaRunner.frame_listeners` (on the loop thread: only hand it over).
5. The loop is closed (robots stopped) and every robot returns to the chargers
   before ``run.json`` is written (its ``setup`` and ``return``: seconds, largest
   pose error, fleet ids, deadlock escapes, collisions). A return that fails stops
   the robots and latches the arena "needs operator" (stopped, the robots named)
   until an operator releases it; after an emergency stop the robots stay where
   they stopped until the release, then return. Between jobs docked simulated
   robots charge for the wall time that passes (:meth:`.ArenaFleet.idle`).

On start (:meth:`ArenaRunner.recover`), jobs the previous server left on the
arena are ``interrupted`` and their partial recordings are recovered with
:func:`swarmdeck.console.recording.recover.recover` into ``recording.mcap``
(the damaged original is kept as ``recording.partial.mcap``), then exported;
exports the previous server left unfinished are written again.
"""
from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from swarmdeck.console.portal.arena_fleet import ArenaFleet
from swarmdeck.console.portal.exports import JobExports, without_server_paths, write_run_json
from swarmdeck.console.portal.files import write_private
from swarmdeck.console.portal.job import Job
from swarmdeck.console.portal.livefeed import LiveFeed
from swarmdeck.console.portal.service import PortalService
from swarmdeck.console.portal.states import ACTIVE, JobState
from swarmdeck.console.runtime.behaviours import TickInput
from swarmdeck.console.runtime.fleet_upkeep import UpkeepConfig, UpkeepResult
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.loop import ControlLoop, DensityParams, LoopConfig, SafetyParams
from swarmdeck.console.runtime.network_frame import NetworkFrame
from swarmdeck.console.sandbox.bundle import ScriptBundle
from swarmdeck.console.sandbox.confinement import ConfinementUnavailable, SandboxLimits
from swarmdeck.console.sandbox.plant import SandboxPlant, script_obstacles_config
from swarmdeck.console.sandbox.run import SandboxOutcome, run_sandboxed
from swarmdeck.console.sandbox.start_poses import arena_start
from swarmdeck.console.sandbox.verification import user_message, without_run_folder
from swarmdeck.core.annotations import Annotations
from swarmdeck.core.annotator import Annotator
from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.constants import CONTROL_PERIOD
from swarmdeck.core.obstacles import Obstacles
from swarmdeck.core.service_thread import ServiceThread
from swarmdeck.devices.clock import RealTimePacer
from swarmdeck.safety.guard import GuardConfig

ENDED_OK = ("script", "duration")


@dataclass(frozen=True)
class ArenaSettings:
    """The arena the runner drives.

    Attributes:
        robots_via: ``mqtt://HOST:PORT`` for networked robots; None: the simulated arena.
        fleet: robots the arena has (the most a job may use).
        bounds: the floor, m.
        dt: control period, s.
        fast: simulated arena only: tick as fast as it computes instead of in real time (the jobs, and the
            robots' set-up and return).
        seed: seed of the simulated arena's random start poses (None: fresh).
        charge: the simulated robots' state of charge when the server starts, scalar or one per robot.
        upkeep: set-up and return limits, which robots may be assigned (``min_charge``).
        guard: the guard of a bypassed barrier (guard distance, intervention threshold); None runs a bypass without
            it — for trusted tests only (contacts on purpose): no command-line option or file sets it.
        obstacles: the floor's line-segment obstacles (``swarmdeck server --obstacles``): in the jobs' barrier, the
            simulation, the fleet's maneuvers and the recordings.
        name: the arena's name behind a portal of several (``--arena NAME=SPEC``; :mod:`.arenas`); None: the
            portal's first arena.
        sensors: the robots' sensors in every job's Frames (``swarmdeck server --sensors``; issue 28.1: Robotarium
            2.0's seven ToF sensors, encoders, IMU and LEDs, :mod:`swarmdeck.console.runtime.tick_sensing`): in the
            recording, the live view (rays and end points), the video and the replay.
        slot: the region (slot of the arena's plan) this runner claims for, on a floor divided into regions
            (:mod:`.region_runner`); None: the whole arena.
    """

    robots_via: str | None = None
    fleet: int = 12
    bounds: Bounds = DEFAULT_BOUNDS
    dt: float = CONTROL_PERIOD
    fast: bool = False
    seed: int | None = None
    charge: float | tuple[float, ...] = 1.0
    upkeep: UpkeepConfig = field(default_factory=UpkeepConfig)
    guard: GuardConfig | None = field(default_factory=GuardConfig)
    obstacles: Obstacles | None = None
    name: str | None = None
    sensors: bool = False
    slot: int | None = None

    @property
    def real_time(self) -> bool:
        return self.robots_via is not None or not self.fast


class SandboxCommands:
    """The loop behaviour that plays the sandboxed script's commands: its nominal look-ahead velocities.

    ``set(nominal)`` (array (N, 2), m/s, or None: the script missed the tick → zero) before each tick;
    :attr:`draw` holds what the script draws (the plant puts its ``draw`` messages there, capped), which
    the loop's Frames carry (:meth:`annotations`).
    """

    name = "script (sandboxed)"

    def __init__(self, bounds: Bounds = DEFAULT_BOUNDS, on_warning: Callable[[str], None] | None = None) -> None:
        self._nominal: NDArray[np.float64] | None = None
        self.network: NetworkFrame | None = None  # a decentralised script's traffic (SandboxPlant.show_network)
        self.draw = Annotator(bounds)
        self._on_warning = on_warning

    def network_frame(self, dt: float) -> NetworkFrame | None:
        """The script's last account of its robots' links and traffic: the Frame's ``network`` (live view, recording)."""
        return self.network

    def annotations(self, time: float) -> Annotations:
        """What the script draws in the tick at ``time`` s (``DrawsAnnotations``); the caps it hit go to
        ``on_warning`` (the loop's events: the job's log and recording)."""
        drawn = self.draw.collect(time)
        for message in self.draw.take_messages():
            if self._on_warning is not None:
                self._on_warning(message)
        return drawn

    def set(self, nominal: NDArray[np.float64] | None) -> None:
        self._nominal = None if nominal is None else np.asarray(nominal, dtype=float)

    def __call__(self, tick: TickInput) -> tuple[NDArray[np.float64], None]:
        if self._nominal is None or self._nominal.shape != (len(tick.poses), 2):
            return np.zeros((len(tick.poses), 2)), None
        return self._nominal.copy(), None


class ArenaRunner:
    """The thread that runs waiting jobs on the arena, one at a time (module docstring).

    ``emergency_stop()`` and ``cancel(job_id)`` are called by the service (any thread).
    """

    def __init__(self, service: PortalService, settings: ArenaSettings, live: LiveFeed | None = None, *,
                 poll_s: float = 1.0, fleet: Any = None, exports: JobExports | None = None) -> None:
        self.service, self.settings = service, settings
        self.live = live if live is not None else LiveFeed()
        self.poll_s = float(poll_s)
        self._thread = ServiceThread(self._run, f"swarmdeck-portal-arena{'-' + settings.name if settings.name else ''}",
                                     join_timeout=15.0)
        self._stop = self._thread.stop_event  # set: the arena thread ends after this pass
        self._lock = threading.Lock()
        self._job: int | None = None
        self._end_job = threading.Event()  # the current job must end now (cancel, e-stop, shutdown)
        self._loop: ControlLoop | None = None
        self.runs = 0
        self.frame_listeners: list[Callable[[Any], None]] = []  # e.g. the operator's viser console
        # CSV, replay, video of ended jobs, in a child process (a remote runner's are the portal's: .remote_runner)
        self.exports = exports if exports is not None else JobExports(service)
        # fleet: the arena's ArenaFleet, or one region's robots of a shared floor (console/portal/region_runner.py)
        self.fleet: Any = fleet if fleet is not None else ArenaFleet(
            settings.fleet, settings.bounds, settings.dt, robots_via=settings.robots_via, seed=settings.seed,
            charge=np.asarray(settings.charge, dtype=float), config=settings.upkeep, fast=settings.fast,
            obstacles=settings.obstacles)
        self.fleet.frame_listeners = self.frame_listeners  # the operator's view sees set-ups and returns too
        self._halt = threading.Event()  # fleet maneuvers must stop now (emergency stop, shutdown)
        self._idle_mark = time.monotonic()  # wall time the simulated fleet has charged up to
        self._upkeep: dict[str, Any] = {}  # the current job's set-up and return, for run.json
        self._safety: dict[str, Any] = {}  # the current job's bypass and contacts, for run.json
        self._barrier: dict[str, Any] | None = None  # the current job's barrier tally (BarrierTally.report)
        self._alerts: tuple[int | None, list[str]] = (None, [])  # the last job's guard and contact events
        self._log: tuple[int | None, bytearray] = (None, bytearray())  # the running job's script output so far
        self._failure: str | None = None  # why the current job must fail (fail_job), None: it ends on its own

    # ------------------------------------------------------------------ control (any thread)
    def start(self) -> ArenaRunner:
        """Start the arena thread (idempotent)."""
        self._thread.start()
        return self

    def stop(self, timeout: float = 15.0) -> None:
        """End the current job (robots stopped) and the thread."""
        self._stop.set()
        self._end_job.set()
        self._halt.set()
        self.service.notify()
        self._thread.stop(timeout)
        self.fleet.close()
        self.exports.stop()

    def emergency_stop(self) -> None:
        self._halt.set()
        with self._lock:
            loop = self._loop
            if self._job is not None:
                self._end_job.set()
        if loop is not None:
            loop.estop()  # the next tick's commands are zero

    def cancel(self, job_id: int) -> None:
        with self._lock:
            if self._job == int(job_id):
                self._end_job.set()

    def fail_job(self, reason: str) -> int | None:
        """End the current job as **failed** with ``reason`` (e.g. its region of a shared floor stalled: the floor
        already stopped its robots); the job's id, or None when none runs. The reason is the job's and run.json's
        ``error``, and an event in its recording."""
        with self._lock:
            job, loop = self._job, self._loop
            if job is None:
                return None
            self._failure = reason
            self._end_job.set()
        if loop is not None:
            loop.post(reason)
        return job

    @property
    def current_job(self) -> int | None:
        return self._job

    def live_log(self, job_id: int) -> bytes | None:
        """The script output of job ``job_id`` so far, while it is the runner's job (None otherwise)."""
        with self._lock:
            job, log = self._log
            return bytes(log) if job == int(job_id) else None

    def _append_log(self, job_id: int, chunk: bytes) -> None:
        with self._lock:
            if self._log[0] == job_id:
                self._log[1].extend(chunk)

    def alerts(self) -> dict[str, Any]:
        """The running (or last) job's guard and contact events, for the operator page: ``{"job", "messages"}``."""
        job, messages = self._alerts
        return {"job": job, "messages": list(messages[-50:])}

    def fleet_status(self) -> dict[str, Any]:
        """The fleet table (:meth:`.ArenaFleet.status`): each robot docked/charging/assigned/away, its charge."""
        return self.fleet.status()

    # ------------------------------------------------------------------ the thread
    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                tidy = self._between_jobs()
            except Exception as exc:  # noqa: BLE001 - never let the arena thread die: the operator is told
                self.service.arena_needs_operator(f"the fleet's upkeep failed: {type(exc).__name__}: {exc}")
                tidy = False
            # a release landing after _between_jobs saw the arena stopped must not let a job start with robots
            # still on the floor: only claim after a pass that found the arena running (and returned them)
            job = self._claim() if tidy else None
            if job is None:
                self.service.wait_for_change(self.poll_s)
                continue
            try:
                self.run_job(job)
            except Exception as exc:  # noqa: BLE001 - never let the arena thread die: the job fails, say why
                self.service.finish_run(job.id, JobState.FAILED, f"the arena runner failed: {type(exc).__name__}: {exc}")
            self._idle_mark = time.monotonic()

    # ------------------------------------------------------------------ the fleet between and around jobs
    def _watch_events(self, frame: Any) -> None:
        """On the loop thread: keep the frame's guard and contact events for the operator page."""
        for event in frame.events:
            if event.startswith(("BARRIER BACK ON", "CONTACT:")):
                self._alerts[1].append(event)

    def _admit(self, job: Job) -> str | None:
        """None when the job's N robots can be assigned now; else why it waits (the robots named)."""
        why = self.fleet.shortfall(job.robots)
        return None if why is None else f"waiting for robots: {why}"

    def _between_jobs(self) -> bool:
        """Docked simulated robots charge for the wall time since the last call; robots left on the floor
        (after an emergency stop was released, a failed set-up, a restart) return to the chargers.
        False when the arena is stopped (no job may be claimed on this pass)."""
        now = time.monotonic()
        self.fleet.idle(now - self._idle_mark)
        self._idle_mark = now
        if self.service.arena_stopped or self._region_stopped():
            return False
        try:
            away = self.fleet.away()
        except ValueError:
            return True  # the fleet cannot be reached: fleet.error says so; the job's admission names it
        if away:
            return bool(self._return_fleet("before the next job")["ok"])
        return True

    def _claim(self) -> Job | None:
        """The next job for this arena (or this region of it: ``ArenaSettings.slot``) from the service (in-process,
        or a remote runner's :class:`~.remote_runner.PortalLink`, which knows no regions)."""
        if self.settings.slot is None:
            return self.service.claim_for_arena(self._admit, arena=self.settings.name)
        return self.service.claim_for_arena(self._admit, arena=self.settings.name, slot=self.settings.slot)

    def _region_stopped(self) -> bool:
        """This runner's region (a floor divided into regions) is latched stopped by an operator: its robots stay
        where they stopped, no job starts there, until the region is released."""
        return self.settings.slot is not None and self.service.stopped_here(self.settings.name, self.settings.slot)

    def _hold_loop(self, loop: ControlLoop | None) -> None:
        """The loop a fleet maneuver runs on, for the emergency stop (None: the maneuver is over)."""
        with self._lock:
            self._loop = loop

    def _set_up(self, job_id: int, poses: NDArray[np.float64]) -> Any:
        """Assign and set up the job's robots at ``poses``; their ports (robots 0…N−1). ValueError naming
        the robots or poses when that fails (the robots are stopped)."""
        t = time.monotonic()
        try:
            result, ports = self.fleet.set_up(job_id, poses, stop=self._end_job.is_set, on_loop=self._hold_loop)
        except ValueError as exc:
            self._upkeep["setup"] = {"ok": False, "message": str(exc), "robots": []}
            raise ValueError(f"set-up refused: {exc}") from None
        self._upkeep["setup"] = _report(result, time.monotonic() - t)
        if ports is None:
            raise ValueError(f"set-up failed: {result.message}")
        return ports

    def _return_fleet(self, when: str) -> dict[str, Any]:
        """Every robot on the floor back to the chargers (unless the arena is stopped); a failure latches
        the arena "needs operator" with the robots named. The return's report."""
        self._halt.clear()  # cleared before the check: an emergency stop from now on halts the return
        if self.service.arena_stopped or self._region_stopped() or self._stop.is_set():
            return {"ok": False, "message": "not returned: the arena is stopped (emergency stop); the robots "
                                            "return to the chargers when an operator releases it", "robots": []}
        t = time.monotonic()
        try:
            result = self.fleet.return_all(stop=self._halt.is_set, on_loop=self._hold_loop)
        except ValueError as exc:
            report: dict[str, Any] = {"ok": False, "message": str(exc), "robots": []}
        else:
            report = _report(result, time.monotonic() - t)
        if not report["ok"] and not self._halt.is_set():
            self.service.arena_needs_operator(f"return to the chargers {when} failed: {report['message']}")
        return report

    def recover(self) -> list[int]:
        """Mark jobs left on the arena ``interrupted`` and recover their partial recordings; their ids."""
        ids = self.service.recover_on_start()
        self.exports.resume()
        recover_recordings(self.service, self.exports, ids)
        return ids

    def run_job(self, job: Job) -> JobState | None:
        """Run one claimed job to its end; its final state."""
        job_id, folder = job.id, self.service.job_dir(job.id)
        self._end_job.clear()
        self._failure = None
        self._upkeep, self._safety, self._barrier = {}, {}, None
        self._alerts = (job_id, [])
        with self._lock:
            self._log = (job_id, bytearray())
        with self._lock:
            self._job = job_id
        if self.service.job_state(job_id) not in ACTIVE:
            self._end_job.set()  # cancelled or e-stopped between the claim and here: nothing moves
        try:
            return self._run_job(job_id, job, folder)
        finally:
            with self._lock:
                self._job, self._loop = None, None

    def _run_job(self, job_id: int, job: Job, folder: Path) -> JobState | None:
        try:
            outcome, note = self._sandboxed(job, folder)
        except ConfinementUnavailable as exc:
            outcome, note = None, str(exc)
        finally:
            with self._lock:
                self._loop = None
            self.live.clear(job_id)
        if outcome is None:
            state, reason = JobState.FAILED, note
        elif outcome.ended_by in ENDED_OK:
            state, reason = JobState.DONE, note
        elif outcome.ended_by == "cancelled":
            state, reason = JobState.CANCELLED, "cancelled"
        else:
            state, reason = JobState.FAILED, outcome.error_line
        if self._failure is not None:  # fail_job: the runner ended it (e.g. its region stalled)
            state, reason = JobState.FAILED, self._failure
        said = _safety_note(self._safety)
        if said:
            reason = f"{reason}; {said}" if reason else said
        reason = None if reason is None else _user_reason(without_server_paths(reason, folder), job, folder)
        ended_by = None if outcome is None else outcome.ended_by
        summary = {"ended_by": "stalled" if self._failure is not None else ended_by, "barrier": self._barrier,
                   "error": reason if state == JobState.FAILED else None,
                   "ticks": None if outcome is None else outcome.ticks,
                   "overruns": None if outcome is None else outcome.overruns, "note": note, **self._safety,
                   **self._upkeep}
        write_run_json(folder, summary)
        if outcome is not None:
            write_private(folder / "script.log", without_run_folder(outcome.log))
        if (folder / "recording.mcap").is_file():
            self.exports.submit(job_id)  # written in the background: the next job starts now
        self.runs += 1
        return self.service.finish_run(job_id, state, reason)

    def _sandboxed(self, job: Job, folder: Path) -> tuple[SandboxOutcome | None, str | None]:
        from swarmdeck.console.recording.recorder import Recorder
        from swarmdeck.console.recording.resimulate import session_metadata
        from swarmdeck.devices.net.mqtt_config import redact_url

        s, cfg = self.settings, self.service.config
        n, duration = job.robots, job.duration
        initial = None if job.initial_poses is None else np.asarray(job.initial_poses, dtype=float)
        bypass = bool(job.bypass)
        # the script's job knows nothing of the console's circling density: none is computed, drawn or recorded
        loop_config = LoopConfig(n_robots=n, dt=s.dt, bounds=s.bounds, seed=s.seed, behaviour="rendezvous",
                                 safety=SafetyParams(enabled=True), density=DensityParams(moving=False),
                                 obstacles=s.obstacles, sensors=s.sensors)
        state: dict[str, Any] = {"loop": None, "recorder": None, "setup_failed": None, "tally": None}
        notes: list[str] = []

        def stopped() -> bool:
            return self._end_job.is_set()

        capsule, capsule_files = _job_capsule(self.service, job, bypass)

        def make_plant(n_script: int, script_initial: NDArray[np.float64] | None,
                       obstacles: NDArray[np.float64] | None = None) -> SandboxPlant:
            poses = arena_start(n_script, n, initial, script_initial, self.fleet.start_poses, s.bounds).poses
            config = loop_config if obstacles is None else script_obstacles_config(loop_config, obstacles, poses)
            try:
                robots = self._set_up(job.id, np.asarray(poses, dtype=float))
            except ValueError as exc:
                state["setup_failed"] = str(exc)
                raise
            notes.append(self._upkeep["setup"]["message"])
            loop = ControlLoop(config, source=robots, sink=robots, clock=time.monotonic if s.real_time else None,
                               guard=s.guard)
            with self._lock:
                self._loop = loop
            state["loop"] = loop
            source = redact_url(s.robots_via) if s.robots_via else "simulation"
            fleet_ids = robots.fleet_ids.tolist()
            rec = Recorder(folder / "recording.mcap", session_metadata(config, None, source=source, guard=s.guard,
                                                                      job=job.id, bypass=bypass,
                                                                      fleet_ids=fleet_ids),
                           capsule=None if capsule is None else capsule.to_dict(), capsule_files=capsule_files)
            loop.post(f"robots 0..{n - 1} are the fleet's robots {', '.join(map(str, fleet_ids))}")
            state["recorder"] = rec
            tally = state["tally"] = BarrierTally(n)

            def publish(frame: Frame) -> None:  # recording, live view (and so video and replay): no density layer
                frame = frame if frame.density is None else replace(frame, density=None)
                rec.write_frame(frame)
                self.live.publish(job.id, frame)
                tally(frame)

            loop.subscribe(publish)
            loop.subscribe(self._watch_events)
            for listener in self.frame_listeners:
                loop.subscribe(listener)
            commands = SandboxCommands(loop_config.bounds, on_warning=loop.post)
            loop.use_behaviour(commands)
            if bypass:
                loop.set_safety(enabled=False)  # the guard stays on (the loop's guard, set above)
                loop.post("barrier bypassed: an operator approved it (verification allowed it, the manifest asked); "
                          "the guard is on")
            if not self.service.mark_running(job.id):
                self._end_job.set()
            loop.pause()
            loop.tick()  # the starting poses, recorded; robots hold still
            loop.run()
            return SandboxPlant.on_loop(loop, commands, duration, RealTimePacer(s.dt) if s.real_time else None)

        # the wall-time limit covers the set-up too (its own time limit; the script waits for it)
        tick_s, overruns = cfg.arena_budget(s.dt, s.real_time)  # real time: one control period by default
        region = None if s.bounds == DEFAULT_BOUNDS else s.bounds  # a region of a shared floor: the script's arena
        limits = SandboxLimits(tick_s=tick_s, max_overruns=overruns, tick_clock="wall" if s.real_time else "cpu",
                               wall_s=duration + cfg.grace_s + s.upkeep.limit(n))
        try:
            script, entry = self.service.script(job)
            outcome = run_sandboxed(script, make_plant, entry=entry, n_robots=n, duration=duration,
                                    limits=limits, trusted=cfg.trusted, cancelled=stopped,
                                    jail=cfg.jail(), bounds=region, params=job.params,
                                    on_log=lambda chunk: self._append_log(job.id, chunk))
        finally:
            loop = state["loop"]
            if loop is not None:
                _record_stop(loop)
                loop.close()  # robots stopped (the fleet's ports stay open)
                self._safety = _safety_report(loop, bypass)
            if state["recorder"] is not None:
                state["recorder"].close()
            if state["tally"] is not None:
                self._barrier = state["tally"].report()
            with self._lock:
                self._loop = None
            self.fleet.end_assignment()
            self._upkeep["return"] = self._return_fleet(f"after job {job.id}")
        if state["setup_failed"] is not None:
            return None, state["setup_failed"]
        return outcome, "; ".join(notes) or None


def recover_recordings(service: PortalService, exports: JobExports, ids: list[int]) -> None:
    """The partial recordings of interrupted jobs ``ids`` recovered
    (:func:`swarmdeck.console.recording.recover.recover` into ``recording.mcap``, the damaged original kept as
    ``recording.partial.mcap``), ``run.json`` saying so, and their exports submitted."""
    from swarmdeck.console.recording.recover import RecoveryError, recover

    for job_id in ids:
        folder = service.job_dir(job_id)
        partial, out = folder / "recording.partial.mcap", folder / "recording.mcap"
        if not out.is_file():
            continue
        out.replace(partial)
        try:
            report = recover(partial, out)
            note = report.summary()
        except (RecoveryError, OSError) as exc:
            note = f"the partial recording could not be recovered: {exc}"
        write_run_json(folder, {"ended_by": "interrupted", "recovery": note})
        if out.is_file():
            exports.submit(job_id)


def _user_reason(reason: str, job: Job, folder: Path) -> str:
    """The job's reason as verification words it (:func:`~swarmdeck.console.sandbox.verification.user_message`): the
    researcher's file name for the stored ``script.py``, and the line of their code an error names."""
    try:
        bundle = (ScriptBundle.single("script.py", (folder / "script.py").read_bytes()) if job.kind == "py"
                  else ScriptBundle.from_path(folder / "src", job.entry))
    except (OSError, ValueError):
        return reason
    return user_message(reason, bundle, job.script if job.kind == "py" else None) or reason


#: the barrier "stepped in" for a robot when it changed its command by more than this, m/s
STEPPED_IN_MPS = 1e-3


class BarrierTally:
    """How often the barrier stepped in during a run, for which robots, and the closest two robots came
    (run.json's ``barrier``; the job page's and ``swarmdeck submit --wait``'s results). Called with each
    Frame on the loop thread: O(N) per tick, vectorised."""

    def __init__(self, n: int) -> None:
        self.ticks = 0
        self.stepped_in = 0
        self.per_robot = np.zeros(n, dtype=np.int64)
        self.min_distance = math.inf

    def __call__(self, frame: Frame) -> None:
        xy = frame.poses[:, :2]
        if len(xy) >= 2:  # the closest pair of robot centres this tick (k-d tree: no N×N matrix)
            d, _ = cKDTree(xy).query(xy, k=2)
            self.min_distance = min(self.min_distance, float(d[:, 1].min()))
        b = frame.barrier
        if b is None:
            return
        self.ticks += 1
        if b.enabled and b.intervention.shape == self.per_robot.shape:
            hit = b.intervention > STEPPED_IN_MPS
            if hit.any():
                self.stepped_in += 1
                self.per_robot += hit

    def report(self) -> dict[str, Any]:
        """``{"ticks", "stepped_in_ticks", "robots": {robot: ticks}, "min_distance_m"}`` (robots 0…N−1 of the
        job; the minimum distance between robot centres, m, None when never measured)."""
        robots = {str(int(k)): int(self.per_robot[k]) for k in np.flatnonzero(self.per_robot)}
        return {"ticks": self.ticks, "stepped_in_ticks": self.stepped_in, "robots": robots,
                "threshold_mps": STEPPED_IN_MPS,
                "min_distance_m": None if not math.isfinite(self.min_distance) else round(self.min_distance, 4)}


def _safety_report(loop: ControlLoop, bypass: bool) -> dict[str, Any]:
    """run.json's ``bypass`` (granted; revoked: tick, t s of run time, why; brake: ticks the guard stopped robots)
    and ``contacts`` (count, robots, episodes) of a finished run."""
    revoked = loop.revocations[0] if loop.revocations else None
    return {"bypass": {"granted": bypass, "revoked": revoked, "brake_ticks": loop.brakes,
                       "guard": {"guard_distance": loop.guard.guard_distance if loop.guard else None,
                                 "max_intervention": loop.guard.max_intervention if loop.guard else None}},
            "contacts": loop.contacts.summary()}


def _safety_note(report: dict[str, Any]) -> str:
    """The job's reason's part about the bypass and contacts (empty when there is nothing to say)."""
    parts = []
    revoked = (report.get("bypass") or {}).get("revoked")
    if revoked:
        parts.append(f"barrier bypass revoked at t = {revoked['t']:.2f} s: {revoked['why']}")
    contacts = report.get("contacts") or {}
    if contacts.get("count"):
        pairs = ", ".join(f"{e['robots'][0]}–{e['robots'][1]}" for e in contacts["episodes"][:10])
        parts.append(f"{contacts['count']} contact(s) between robots ({pairs})")
    return "; ".join(parts)


def _job_capsule(service: PortalService, job: Job, bypass: bool) -> tuple[Any, dict[str, bytes]]:
    """What reproduces ``job`` (``swarmdeck capsule``, the job's ``capsule.zip``): its stored script files (with
    their SHA-256), entry, robots, duration, bypass; the loop, guard and start poses are in its recording.
    (None, {}) when the stored script cannot be read (the run names that itself)."""
    from swarmdeck.console.recording.capsule import manifest_for
    from swarmdeck.console.recording.capsule_zip import CapsuleError, script_files

    try:
        path, entry = service.script(job)
        files, main = script_files(path, entry)
    except (CapsuleError, OSError, ValueError):
        return None, {}
    run: dict[str, Any] = {"robots": int(job.robots), "duration": float(job.duration), "bypass": bool(bypass), "job": int(job.id),
           "single": not path.is_dir(), "sandbox": True}
    if job.params is not None:  # the script's parameter values (the manifest's, or a sweep's best point)
        run["params"] = dict(job.params)
    return manifest_for("portal", files, entry=main, run=run), files


def _record_stop(loop: ControlLoop) -> None:
    """An emergency stop the run ended on before the loop ticked again: one more tick (its commands are zero),
    so that the recording, its exports and the replay show the stop ("estop" run state, "EMERGENCY STOP")."""
    latest = loop.latest
    if loop.run_state == "estop" and (latest is None or latest.run_state != "estop"):
        loop.tick()


def _report(result: UpkeepResult, wall_s: float) -> dict[str, Any]:
    """A set-up's or return's entry in run.json: ok, robots (fleet ids), seconds (the maneuver's own time),
    wall_s, largest position/heading error, collisions, deadlock escapes, message."""
    return {**result.to_dict(), "wall_s": round(wall_s, 3)}
