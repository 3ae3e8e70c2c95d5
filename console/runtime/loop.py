"""The control loop (DESIGN.md "One tick"): sense → inputs → control → safety+actuation → send → Frame.

:class:`ControlLoop` runs in its own thread at the control period
(:meth:`start`), or one tick at a time on a virtual clock (:meth:`tick`, for
tests and benchmarks). Every tick produces one immutable
:class:`~swarmdeck.console.runtime.frame.Frame`, handed to subscribers (the viser
scene, the recorder) and kept as :attr:`latest`. Subscribers run on the loop
thread and must only hand the Frame over (the console's viewer stores it and
draws on its own thread, so a slow browser never slows the loop).

The tick reads top to bottom as its stages:

1. **sense** — the pose source's ``(ids, poses, seen)``; rows with a non-finite
   pose are not seen; pairs of seen robots that come into contact (the rps test) are one
   event each per episode, alerted while they last and kept in :attr:`ControlLoop.contacts`
   (:mod:`swarmdeck.console.runtime.contacts`); robots that report a battery below
   :attr:`ControlLoop.battery_watch` ``.warn_below`` (and are not charging) raise the
   "battery low" alert naming them (:mod:`swarmdeck.console.runtime.batteries`);
2. **inputs** — contacts from the input hub become density bumps; the density
   snapshot the behaviours see; one health line per port;
3. **control** — the behaviour's nominal look-ahead velocities ``(N, 2)``
   (unseen robots zero, at most ``max_speed``);
4. **safety and actuation** — :func:`swarmdeck.devices.pipeline.certify`, the
   pipeline ``Arena.step`` uses too: look-ahead map, wheel limits by one uniform
   scale, the unicycle barrier with the wheel-limit rows (unseen robots and the
   sink's ``obstacles()`` as fixed obstacles), fail-stop. With the barrier switched
   off (by a person: the console's operator, or the portal runner for a bypass an
   operator approved) the **guard** runs (:mod:`swarmdeck.safety.guard`,
   :func:`~swarmdeck.devices.pipeline.certify_bypassed`): walls and obstacles stay
   hard, the full barrier watches, and the first time a pair would come closer than
   the guard distance or the barrier would have intervened by more than the threshold,
   the barrier is switched back on (event "BARRIER BACK ON", :attr:`ControlLoop.revocations`);
   from the first bypassed tick on, robots that would still bring a pair closer than the
   guard distance are stopped (:func:`~swarmdeck.devices.pipeline.brake`). Only
   ``ControlLoop(guard=None)`` (trusted code, never a setting) runs without it;
5. **send** — the command sink gets ``(ids, v, ω)``, or ``hold()`` while paused;
6. **Frame** — everything above, to every subscriber.

One error policy covers every stage (:meth:`~swarmdeck.console.runtime.tick.Ticker._stage`): a stage that
raises is counted in :attr:`ControlLoop.errors`, raises a visible alert in the
Frame (cleared when the stage next succeeds), and — for sense, control and
safety — every robot gets zero for that tick; the loop keeps running.

Clocks. The one time base a user sees and seeks to is *session time*: seconds
since the session's first Frame (``Frame.time − ControlLoop.time_origin``). The
panel's status line ``t``, its plots' x axis and its alert times, ``swarmdeck
info``'s event times and ``swarmdeck play``'s timeline (``--start``) are all in
it (a recording starts with the console, so recording time is session time).
The others are labelled where they appear: ``Frame.time`` is the loop's clock
(monotonic, arbitrary origin; input datagrams are stamped with it); ``run t``
(``Frame.run_time``) is the behaviours' time, which stops while paused; the
simulator's health line shows its own clock, which also stops while paused.

Operator commands (:meth:`run`, :meth:`pause`, :meth:`step`, :meth:`estop`,
behaviour and parameter changes, density bumps) are thread-safe and take
effect at the start of the next tick. The emergency stop zeroes every command
of the next tick and every tick after it until :meth:`release` (which leaves
the loop paused). Each command is a typed operator event
(:mod:`swarmdeck.console.runtime.operator_events`) that the loop hands, stamped with the tick it
takes effect in, to :meth:`subscribe_operator` listeners (the recorder) and that re-simulation replays.

The parts, each in its own module: the operator's commands and state
(:mod:`swarmdeck.console.runtime.commands`, of which :class:`ControlLoop` is one), the stages of one
tick (:mod:`swarmdeck.console.runtime.tick`), the messages and alerts
(:mod:`swarmdeck.console.runtime.notices`); this module puts them together and runs the thread.
"""
from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from swarmdeck.console.runtime.batteries import BatteryWatch
from swarmdeck.console.runtime.commands import OperatorCommands, close_behaviour
from swarmdeck.console.runtime.contacts import ContactWatch
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.notices import Notices
from swarmdeck.console.runtime.params import DensityParams, LoopConfig, SafetyParams
from swarmdeck.console.runtime.tick import Ticker
from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.core.ports import CommandSink, PoseSource, close_ports
from swarmdeck.core.service_thread import ServiceThread
from swarmdeck.devices import ArenaConfig
from swarmdeck.devices.clock import RealTimePacer
from swarmdeck.devices.simulated_robots import SimulatedRobots
from swarmdeck.safety.guard import GuardConfig

FrameListener = Callable[[Frame], None]

#: Names other modules import from here (the parameter classes live in params.py).
__all__ = ["ControlLoop", "DensityParams", "FrameListener", "LoopConfig", "SafetyParams"]


class ControlLoop(OperatorCommands):
    """The console's control loop. See the module docstring; the operator's commands are those of
    :class:`~swarmdeck.console.runtime.commands.OperatorCommands`.

    Args:
        config: initial settings.
        source, sink: where poses come from / commands go; both default to one
            :class:`SimulatedRobots` (N = ``config.n_robots``, seeded by ``config.seed``).
        inputs: an ``swarmdeck.inputs.InputHub`` (started by the caller) whose contacts
            become density bumps through ``contact_density`` (a ``ContactDensity``).
        clock: the loop's clock in s; None → virtual (tick × dt).
        robot: the robot model (look-ahead ℓ, wheel limits).
        guard: what watches the robots while the barrier is off (module docstring, stage 4); None runs
            without it — for trusted tests only: no setting, file or script can reach it.
    """

    def __init__(self, config: LoopConfig | None = None, *, source: PoseSource | None = None,
                 sink: CommandSink | None = None, inputs: Any = None, contact_density: Any = None,
                 clock: Callable[[], float] | None = None, robot: GritsBotParams | None = None,
                 guard: GuardConfig | None = GuardConfig()) -> None:
        cfg = config if config is not None else LoopConfig()
        robot = robot if robot is not None else GritsBotParams()
        if source is None or sink is None:
            sim = SimulatedRobots(cfg.n_robots, ArenaConfig(bounds=cfg.bounds, dt=cfg.dt, seed=cfg.seed,
                                                                  obstacles=cfg.obstacles), robot)
            source = source if source is not None else sim
            sink = sink if sink is not None else sim
        self.source, self.sink = source, sink
        self.inputs = inputs
        if inputs is not None and contact_density is None:
            from swarmdeck.inputs import ContactDensity

            contact_density = ContactDensity()
        self.contact_density = contact_density
        self._clock = clock
        notices = Notices()
        super().__init__(cfg, robot, guard, notices, lambda: self._ticker.run_time)
        self._ticker = Ticker(cfg, robot, guard, source, sink, inputs, contact_density, self.density, notices,
                              self.barrier_back_on)
        self._listeners: list[FrameListener] = []
        self.latest: Frame | None = None
        self._thread = ServiceThread(self._run_forever, "swarmdeck-loop", join_timeout=2.0)
        self.overruns = 0

    # ------------------------------------------------------------------ what the ticks keep
    @property
    def errors(self) -> dict[str, int]:
        """Errors counted by stage ("source", "behaviour", "safety", …, "listener", "tick")."""
        return self.notices.errors

    @property
    def run_time(self) -> float:
        """Behaviour time, s: advances by dt only on ticks with motion."""
        return self._ticker.run_time

    @property
    def time_origin(self) -> float | None:
        """The loop clock at the first tick (``Frame.time`` of the first Frame), s; None before it.
        Session time = ``Frame.time − time_origin`` (see the module docstring, "Clocks")."""
        return self._ticker.time_origin

    @property
    def revocations(self) -> list[dict[str, Any]]:
        """Each time the guard switched the barrier back on: tick, run time t, why, closest, intervention."""
        return self._ticker.revocations

    @property
    def brakes(self) -> int:
        """Ticks on which the guard's brake stopped robots."""
        return self._ticker.brakes

    @property
    def contacts(self) -> ContactWatch:
        """Contact episodes between robots (stage 1)."""
        return self._ticker.contacts

    @property
    def battery_watch(self) -> BatteryWatch:
        """When a robot's battery counts as low (stage 1)."""
        return self._ticker.battery_watch

    # ------------------------------------------------------------------ listeners
    def post(self, message: str) -> None:
        """Add a message to the next Frame's events (thread-safe)."""
        self.notices.post(message)

    def add_health(self, name: str, fn: Callable[[], str]) -> None:
        """Show ``fn()`` under ``name`` in every Frame's ``health`` (e.g. the recorder's state)."""
        with self._lock:
            self._ticker.health_fns[str(name)] = fn

    def subscribe(self, listener: FrameListener) -> Callable[[], None]:
        """Call ``listener(frame)`` on the loop thread after every tick; returns an unsubscribe function."""
        with self._lock:
            self._listeners.append(listener)

        def unsubscribe() -> None:
            with self._lock:
                if listener in self._listeners:
                    self._listeners.remove(listener)

        return unsubscribe

    # ------------------------------------------------------------------ the tick
    def tick(self) -> Frame:
        """Run one tick now and return its Frame (virtual clock unless a clock was given): the operator's
        commands since the last tick take effect (their events go to :meth:`subscribe_operator` listeners),
        then the stages of :class:`~swarmdeck.console.runtime.tick.Ticker`, then every subscriber gets the Frame."""
        started = time.perf_counter()
        index = self._ticker.index
        now = self._clock() if self._clock is not None else index * self.config.dt
        settings = self.begin_tick(index, now)
        self.tell_operator_listeners(settings.events)
        frame = self._ticker.run(settings, now, started)
        self.latest = frame
        self._publish(frame)
        return frame

    def _publish(self, frame: Frame) -> None:
        """Hand the Frame to every subscriber; a failing one is counted and reported, the rest still run."""
        with self._lock:
            listeners = list(self._listeners)
        for listener in listeners:
            try:
                listener(frame)
            except Exception as exc:
                self.notices.count("listener")
                self.post(f"frame listener failed: {type(exc).__name__}: {exc}")

    # ------------------------------------------------------------------ threaded running
    def start(self) -> ControlLoop:
        """Run :meth:`tick` every ``dt`` seconds (monotonic clock) on a daemon thread."""
        if self._thread.alive:
            return self
        if self._clock is None:
            t0 = time.monotonic() - self._ticker.index * self.config.dt
            self._clock = lambda: time.monotonic() - t0
        self._thread.start()
        return self

    def _run_forever(self) -> None:
        pacer = RealTimePacer(self.config.dt)
        while not self._thread.stopping:
            try:
                self.tick()
            except Exception as exc:  # never let the thread die silently
                self.notices.count("tick")
                self.post(f"tick failed: {type(exc).__name__}: {exc}")
                try:
                    self.sink.hold()
                except Exception:
                    self.notices.count("sink")
            pacer.wait()
        self.overruns = pacer.overruns

    def stop(self, timeout: float = 2.0) -> None:
        """Stop the thread (robots stop: the sink is closed by :meth:`close`)."""
        self._thread.stop(timeout)

    def close(self) -> None:
        """Stop the thread, stop the robots, close the sink, the inputs and the behaviour (a script's worker)."""
        self.stop()
        close_behaviour(self._behaviour)
        try:
            close_ports(self.source, self.sink)
        finally:
            if self.inputs is not None:
                self.inputs.close()
