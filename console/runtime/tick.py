"""One tick of the control loop (DESIGN.md "One tick"): sense → inputs → control → safety+actuation → send → Frame.

:class:`Ticker` runs the stages of one tick with the :class:`~swarmdeck.console.runtime.commands.TickSettings`
the operator's commands gave it (taken at the tick's start) and returns its
:class:`~swarmdeck.console.runtime.frame.Frame`; it owns what the tick itself keeps from tick to tick
(tick index, run time, the last poses, contact episodes, battery warnings, the guard's state). The stages,
the one error policy and the guard are described in :mod:`swarmdeck.console.runtime.loop`.
"""
from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace
from typing import Any, cast

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.runtime.batteries import BatteryWatch, low_battery_alert
from swarmdeck.console.runtime.behaviours import (
    Behaviour,
    BehaviourError,
    DrawsAnnotations,
    HoldsRobots,
    ReportsHealth,
    ReportsNetwork,
    TickInput,
    goal_params,
)
from swarmdeck.console.runtime.commands import TickSettings
from swarmdeck.console.runtime.contacts import ContactWatch
from swarmdeck.console.runtime.density import ConsoleDensity
from swarmdeck.console.runtime.frame import BarrierFrame, ContactsFrame, CoverageFrame, Frame
from swarmdeck.console.runtime.network_frame import NetworkFrame
from swarmdeck.console.runtime.notices import Notices
from swarmdeck.console.runtime.params import LoopConfig, SafetyParams, frame_params
from swarmdeck.console.runtime.sensors_frame import SensorsFrame
from swarmdeck.console.runtime.tick_sensing import TickSensing
from swarmdeck.core.annotations import Annotations
from swarmdeck.core.kinematics import GritsBotParams, lookahead_points, saturate
from swarmdeck.core.ports import CommandSink, PoseSource, ProvidesImage, SensedPoses, obstacles_of
from swarmdeck.coverage.density import GaussianMixture
from swarmdeck.devices.pipeline import Certified, brake, certify, certify_bypassed
from swarmdeck.safety.guard import GuardCheck, GuardConfig


def _checked(sensed: Any) -> SensedPoses:
    """A pose reading as arrays of the right shapes (ValueError naming the problem otherwise).
    Rows with a non-finite pose are not seen (they get zero commands) and are drawn at the origin."""
    ids = np.asarray(sensed.ids, dtype=np.int64).reshape(-1)
    poses = np.asarray(sensed.poses, dtype=float)
    seen = np.asarray(sensed.seen, dtype=bool).reshape(-1)
    n = len(ids)
    if poses.shape != (n, 3) or seen.shape != (n,):
        raise ValueError(f"pose source gave ids {ids.shape}, poses {poses.shape}, seen {seen.shape}; "
                         f"expected (N,), (N, 3), (N,)")
    finite = np.all(np.isfinite(poses), axis=1)
    if not finite.all():
        poses = np.where(finite[:, None], poses, 0.0)
        seen = seen & finite
    extra = {}
    for name, dtype in (("is_virtual", bool), ("battery", float), ("charging", bool)):
        value = getattr(sensed, name, None)
        if value is not None:
            arr = np.asarray(value, dtype=dtype).reshape(-1)
            if arr.shape != (n,):
                raise ValueError(f"pose source gave {name} {arr.shape} for {n} robots; expected ({n},)")
            extra[name] = arr
    return SensedPoses(ids, poses, seen, is_virtual=extra.get("is_virtual"), battery=extra.get("battery"),
                       charging=extra.get("charging"))


class Stage:
    """One stage's outcome under the loop's error policy (:meth:`Ticker._stage`)."""

    def __init__(self) -> None:
        self.failed = False
        self.error: Exception | None = None
        self.alert: str | None = None
        self.counted = False

    def warn(self, message: str, *, count: bool = False) -> None:
        """The stage ran but the operator should know (shown as its alert; ``count``: an error)."""
        self.alert, self.counted = message, count


def _min_distance(points: NDArray[np.float64]) -> float:
    if len(points) < 2:
        return math.inf
    from scipy.spatial import cKDTree  # lazy: see test_devices_rps_startup_imports

    d, _ = cKDTree(points).query(points, k=2)
    return float(d[:, 1].min())


class Ticker:
    """The stages of one tick over the loop's ports (see the module docstring).

    ``barrier_back_on()`` is called when the guard revokes a bypass (the operator state turns the barrier on).
    """

    def __init__(self, config: LoopConfig, robot: GritsBotParams, guard: GuardConfig | None, source: PoseSource,
                 sink: CommandSink, inputs: Any, contact_density: Any, density: ConsoleDensity, notices: Notices,
                 barrier_back_on: Callable[[], None]) -> None:
        self.config, self.robot, self.guard = config, robot, guard
        self.source, self.sink, self.inputs, self.contact_density = source, sink, inputs, contact_density
        self.density, self.notices = density, notices
        self._lock = notices.lock
        self._barrier_back_on = barrier_back_on
        self.health_fns: dict[str, Callable[[], str]] = {}
        self.index = 0  # the next tick's index
        self.run_time = 0.0  # behaviour time, s: advances by dt only on ticks with motion
        self.time_origin: float | None = None
        self.braking = False  # from the first bypassed tick on, the guard's brake holds
        self.revocations: list[dict[str, Any]] = []  # each time the guard switched the barrier back on
        self.brakes = 0  # ticks on which the guard's brake stopped robots
        self.contacts = ContactWatch()
        self.battery_watch = BatteryWatch()
        self.last_sensed: SensedPoses | None = None
        self.sensing = TickSensing(config) if config.sensors else None  # the robots' sensors (issue 28.1)

    @contextmanager
    def _stage(self, key: str, failure: str, *, stops: bool = True) -> Iterator[Stage]:
        """The tick's one error policy, around one stage.

        If the stage raises: count it under ``errors[key]``, raise the alert ``key`` as
        "<failure>: <Type>: <message>[; robots stopped]", keep the stage's stopped defaults and
        (``stops``) send zero to every robot this tick; the loop keeps running. Otherwise the
        alert ``key`` shows what the stage :meth:`Stage.warn`-ed, or is cleared.
        """
        stage = Stage()
        try:
            yield stage
        except Exception as exc:  # a failing stage stops the robots, tells, and the loop keeps running
            stage.failed, stage.error = True, exc
            self.notices.count(key)
            message: str | None = f"{failure}: {type(exc).__name__}: {exc}" + ("; robots stopped" if stops else "")
        else:
            if stage.counted:
                self.notices.count(key)
            message = stage.alert
        self.notices.alert(key, message)

    def run(self, s: TickSettings, now: float, started: float) -> Frame:
        """Run one tick at loop clock ``now`` (s) with settings ``s``; ``started``: its ``perf_counter`` start."""
        marks = [started]
        behaviour, filt, sp, estop, hard, active = s.behaviour, s.filt, s.safety, s.estop, s.hard, s.active
        run_state = s.run_state
        if self.time_origin is None:
            self.time_origin = now

        # 1. sense: this tick's poses (if the source fails: the last poses, nobody seen)
        with self._stage("source", "pose source failed") as sense:
            sensed = self._sense(now)
        if sense.failed:
            sensed = self._nobody_seen(sense.error)
        ids, poses, seen = sensed.ids, sensed.poses, sensed.seen
        n, points = len(ids), lookahead_points(poses, self.robot.lookahead)
        with self._stage("contacts", "contact detection failed", stops=False):
            self._watch_contacts(ids, poses, seen)
        with self._stage("battery", "battery check failed", stops=False) as batteries:
            if sensed.battery is not None:  # robots that report their battery: warn when one runs low
                low = low_battery_alert(ids, sensed.battery, sensed.charging if sensed.charging is not None
                                        else np.zeros(n, dtype=bool), self.battery_watch)
                if low is not None:
                    batteries.warn(low)
        marks.append(time.perf_counter())

        # 2. inputs: contacts -> density bumps; the density snapshot behaviours see; health lines
        health, contacts, mixture, snapshot = self._health(behaviour), ContactsFrame(), None, None
        if self.inputs is not None:
            with self._stage("inputs", "inputs failed", stops=False):
                contacts, mixture = self._poll_inputs(now, health)
            self.density.contacts = mixture
        with self._stage("density", "density failed", stops=False):
            snapshot = self.density.at(self.run_time)
        marks.append(time.perf_counter())

        # 3. control: the behaviour's nominal look-ahead velocities, within max_speed
        nominal, coverage, movable = np.zeros((n, 2)), None, seen
        with self._stage("behaviour", f"{behaviour.name} failed") as control:
            nominal, coverage = self._control(behaviour, control, poses, points, ids, seen)
            if isinstance(behaviour, HoldsRobots):  # robots it holds in place: fixed obstacles of the barrier
                movable = seen & ~np.asarray(behaviour.fixed(ids), dtype=bool).reshape(n)
        nominal[~movable] = 0.0
        nominal = saturate(nominal, self.config.max_speed)
        marks.append(time.perf_counter())

        # 4. safety and actuation: the pipeline Arena.step uses too (look-ahead map, wheel limits, barrier)
        cert = None
        with self._stage("safety", "safety filter failed") as safety:
            if sp.enabled or hard is None or self.guard is None:
                cert, barrier = self._certify(filt if sp.enabled else None, sp, poses, points, nominal, movable, safety)
            else:
                cert, barrier = self._certify_guarded(filt, hard, self.guard, sp, ids, poses, points, nominal, movable,
                                                      safety)
            if sp.enabled and self.braking and self.guard is not None and cert is not None:
                cert = self._brake(cert, poses, movable)  # after a bypass (a guarded tick brakes by itself)
            if sp.enabled:
                self.notices.alert("guard", None)  # the barrier is on: nothing for the guard to watch
        if cert is None or not active or sense.failed or control.failed:
            v, w, safe = np.zeros(n), np.zeros(n), np.zeros((n, 2))
        else:
            v, w, safe = cert.v, cert.w, (cert.safe if sp.enabled or self.braking else nominal.copy())
        if safety.failed:
            barrier = BarrierFrame(enabled=True, ok=False, status=f"{type(safety.error).__name__}: {safety.error}",
                                   min_distance=_min_distance(points), intervention=np.zeros(n),
                                   safety_distance=sp.safety_distance)
        marks.append(time.perf_counter())

        # 5. send (paused: hold; robots stop by themselves when commands go stale)
        with self._stage("sink", "command sink failed", stops=False):
            if active or estop:
                self.sink.send(ids, v, w)
            else:
                self.sink.hold()
        marks.append(time.perf_counter())

        # 6. the Frame (the loop hands it to every subscriber), with what the robots sensed at these poses
        sensors = None
        if self.sensing is not None:
            with self._stage("sensors", "sensors failed", stops=False):
                sensors = self.sensing.read(self.source, poses, v, w)
        network = None
        if isinstance(behaviour, ReportsNetwork):  # the robots' communication graph (a decentralised behaviour)
            with self._stage("network", "network layer failed", stops=False):
                network = behaviour.network_frame(self.config.dt)
        drawn = behaviour.annotations(self.run_time) if isinstance(behaviour, DrawsAnnotations) else None
        frame = self._frame(now, sensed, points, nominal, safe, v, w, barrier, coverage, snapshot, contacts,
                            behaviour.name, run_state, s, health, marks, sensors, network, drawn)
        self.index += 1
        if active:
            self.run_time += self.config.dt
        return frame

    # ------------------------------------------------------------------ the stages' bodies
    def _sense(self, now: float) -> SensedPoses:
        sensed = _checked(self.source.read(now))
        self.last_sensed = sensed
        return sensed

    def _nobody_seen(self, error: Exception | None) -> SensedPoses:
        """The last poses with nobody seen (robots get zero); re-raises ``error`` before any reading."""
        prev = self.last_sensed
        if prev is None:
            assert error is not None
            raise error
        return replace(prev, seen=np.zeros(len(prev.ids), dtype=bool))

    def _health(self, behaviour: Behaviour) -> dict[str, str]:
        """One line per port and per registered health function (a failing one shows its error)."""
        with self._lock:
            fns = [("robots", self.source.health)]
            if isinstance(behaviour, ReportsHealth):  # a script's worker, a fleet maneuver's progress
                name = behaviour.name
                fns.append(("script" if name.startswith("script:") else name, behaviour.health))
            if cast(object, self.source) is not self.sink:
                fns.append(("commands", self.sink.health))
            fns += list(self.health_fns.items())
        health: dict[str, str] = {}
        for name, fn in fns:
            try:
                health[name] = str(fn())
            except Exception as exc:  # a health line never stops the tick
                health[name] = f"error: {type(exc).__name__}: {exc}"
        return health

    def _poll_inputs(self, now: float, health: dict[str, str]) -> tuple[ContactsFrame, GaussianMixture]:
        """This tick's contacts (for the Frame) and their density (for the behaviours); adds input health."""
        snap = self.inputs.poll(now)
        self.contact_density.update(snap.contacts, now)
        mixture = self.contact_density.at(now)
        contacts = ContactsFrame.from_contacts(snap.contacts)
        for h in snap.health:
            state = "LOST" if h.lost else f"{h.rate_hz:.0f} Hz"
            errs = f", {h.error_count} errors" if h.error_count else ""
            health[h.name] = f"{state}, {h.contacts} contacts{errs}"
        return contacts, mixture

    def _control(self, behaviour: Behaviour, stage: Stage, poses: NDArray[np.float64], points: NDArray[np.float64],
                 ids: NDArray[np.int64], seen: NDArray[np.bool_]) -> tuple[NDArray[np.float64], CoverageFrame | None]:
        """The behaviour's (N, 2) velocities (non-finite rows zeroed and warned) and its coverage state."""
        n = len(ids)
        if n == 0:
            raise BehaviourError("no robots to control (none seen or all excluded)")
        raw, state = behaviour(TickInput(poses.copy(), points.copy(), self.run_time, self.density,
                                         self.config.bounds, self.config.max_speed, ids.copy(), seen.copy()))
        arr = np.asarray(raw, dtype=float) if not isinstance(raw, np.ndarray) else raw.astype(float, copy=True)
        if arr.shape != (n, 2):
            raise BehaviourError(f"behaviour returned shape {arr.shape}, expected ({n}, 2) velocities in m/s")
        bad = ~np.all(np.isfinite(arr), axis=1)
        arr[bad] = 0.0
        if bad.any():
            stage.warn(f"{behaviour.name}: non-finite command for robot(s) {ids[bad].tolist()}; "
                       "those robots stopped", count=True)
        return arr, (CoverageFrame.from_state(state) if state is not None else None)

    def _certify(self, filt: Any, sp: SafetyParams, poses: NDArray[np.float64], points: NDArray[np.float64],
                 nominal: NDArray[np.float64], seen: NDArray[np.bool_], stage: Stage) -> tuple[Certified, BarrierFrame]:
        """:func:`~swarmdeck.devices.pipeline.certify` with the sink's obstacles, and its BarrierFrame."""
        n, d_s = len(poses), sp.safety_distance
        if filt is None:
            stage.warn("safety barrier OFF")
            return certify(poses, nominal, self.robot, None, seen=seen), BarrierFrame(
                enabled=False, status="off", min_distance=_min_distance(points), intervention=np.zeros(n),
                safety_distance=d_s)
        cert = certify(poses, nominal, self.robot, filt, seen=seen, obstacles=obstacles_of(self.sink))
        if cert.diagnostics is None:
            barrier = BarrierFrame(ok=cert.ok, status=cert.status, intervention=np.zeros(n), safety_distance=d_s)
        else:
            barrier = BarrierFrame.from_diagnostics(cert.diagnostics, n, d_s, enabled=True)
        if not cert.ok:
            barrier = replace(barrier, ok=False, status=cert.status)
            stage.warn(f"safety filter: {cert.status}; robots stopped")
        return cert, barrier

    def _watch_contacts(self, ids: NDArray[np.int64], poses: NDArray[np.float64], seen: NDArray[np.bool_]) -> None:
        """Contacts of this tick's poses: one event per new episode, an alert while any lasts."""
        new = self.contacts.update(self.index, self.run_time, ids, poses, seen)
        touching = sorted(self.contacts.touching)
        with self._lock:
            for contact in new:
                self.notices.post(contact.message())
            self.notices.alert("contact", None if not touching else
                        "robots in contact: " + ", ".join(f"{a}–{b}" for a, b in touching[:10]), event=False)

    def _certify_guarded(self, filt: Any, hard: Any, guard: GuardConfig, sp: SafetyParams, ids: NDArray[np.int64],
                         poses: NDArray[np.float64], points: NDArray[np.float64], nominal: NDArray[np.float64],
                         seen: NDArray[np.bool_], stage: Stage) -> tuple[Certified, BarrierFrame]:
        """A tick with the barrier off and the guard on (module docstring, stage 4)."""
        n, d_s = len(poses), sp.safety_distance
        cert, full, check, stopped = certify_bypassed(poses, nominal, self.robot, hard, filt, guard, self.config.dt,
                                                      seen=seen, obstacles=obstacles_of(self.sink),
                                                      names=ids)
        self.braking = True
        self._braked(stopped)
        if check.trip:
            self._revoke(check)
        diag = cert.diagnostics
        if diag is None:
            barrier = BarrierFrame(enabled=check.trip, ok=cert.ok, status=cert.status, intervention=np.zeros(n),
                                   min_distance=_min_distance(points), safety_distance=d_s)
        else:
            barrier = BarrierFrame.from_diagnostics(diag, n, d_s, enabled=check.trip)
        if not check.trip:
            barrier = replace(barrier, status=f"off, guard on ({barrier.status})", min_distance=_min_distance(points))
        if not cert.ok:
            stage.warn(f"safety filter: {cert.status}; robots stopped")
        elif not check.trip:
            stage.warn("safety barrier OFF")
        with self._lock:
            self.notices.alert("guard", None if check.trip else (
                f"guard on: walls and docked robots hard; pairs watched (guard distance {guard.guard_distance:g} m, "
                f"intervention threshold {guard.max_intervention:g} m/s)"), event=False)
        return cert, barrier

    def _revoke(self, check: GuardCheck) -> None:
        """The guard tripped: the barrier is on again (until a person switches it off again), and says why."""
        entry = {"tick": self.index, "t": round(self.run_time, 3), "why": check.reason,
                 "closest": None if check.closest == math.inf else round(check.closest, 4),
                 "intervention": round(check.intervention, 4)}
        with self._lock:
            self.revocations.append(entry)
            self._barrier_back_on()
            self.notices.post(f"BARRIER BACK ON: the bypass is revoked at t = {self.run_time:.2f} s: {check.reason}")
            self.notices.standing("revoked",
                                  f"barrier back on (bypass revoked at t = {self.run_time:.2f} s): {check.reason}")

    def _brake(self, cert: Certified, poses: NDArray[np.float64], seen: NDArray[np.bool_]) -> Certified:
        """The guard's last resort (stage 4): robots that would bring a pair closer than the guard distance stop."""
        assert self.guard is not None
        out, stopped = brake(cert, poses, self.robot, self.config.dt, self.guard.guard_distance, seen=seen,
                             obstacles=obstacles_of(self.sink))
        self._braked(stopped)
        return out

    def _braked(self, stopped: NDArray[np.bool_]) -> None:
        """Count and alert the guard's brake (robots stopped this tick)."""
        assert self.guard is not None
        if stopped.any():
            self.brakes += 1
        with self._lock:
            self.notices.alert("brake", None if not stopped.any() else
                        f"guard: robots stopped that would come closer than {self.guard.guard_distance:g} m",
                        event=False)

    def _frame(self, now: float, sensed: SensedPoses, points: NDArray[np.float64], nominal: NDArray[np.float64],
               safe: NDArray[np.float64], v: NDArray[np.float64], w: NDArray[np.float64], barrier: BarrierFrame,
               coverage: CoverageFrame | None, snapshot: GaussianMixture | None, contacts: ContactsFrame,
               behaviour: str, run_state: str, s: TickSettings, health: dict[str, str], marks: list[float],
               sensors: SensorsFrame | None = None, network: NetworkFrame | None = None,
               annotations: Annotations | None = None) -> Frame:
        events, alerts = self.notices.take()
        bp = s.behaviour_params
        params = frame_params(bp, s.safety, s.density, self.config)
        if behaviour == "goto":  # the goals, for the scene's goal markers (live and in playback)
            params.update(goal_params(bp))
        timing = {name: b - a for name, a, b in zip(("sense", "inputs", "control", "safety", "actuate"),
                                                     marks, marks[1:])}
        timing["total"] = time.perf_counter() - marks[0]
        image_ref = self.source.image_ref if isinstance(self.source, ProvidesImage) else None
        return Frame(
            tick=self.index, time=now, run_time=self.run_time, dt=self.config.dt, bounds=self.config.bounds,
            lookahead=self.robot.lookahead, poses=sensed.poses, ids=sensed.ids, seen=sensed.seen, nominal=nominal,
            safe=safe, v=v, w=w, barrier=barrier, coverage=coverage, density=snapshot, contacts=contacts,
            behaviour=behaviour, run_state=run_state, params=params, events=events, alerts=alerts, health=health,
            timing=timing, image_ref=image_ref if isinstance(image_ref, str) else None,
            is_virtual=sensed.is_virtual, battery=sensed.battery, charging=sensed.charging, sensors=sensors,
            obstacles=self.config.obstacles, network=network,
            annotations=annotations if annotations is not None and len(annotations) else None,
        )

