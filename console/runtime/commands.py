"""The operator's commands to a running loop (DESIGN.md "One tick"; issue 25 items 3 and 5).

:class:`OperatorCommands` is the thread-safe half of the
:class:`~swarmdeck.console.runtime.loop.ControlLoop`: run, pause, step, emergency stop and release,
behaviour switches, behaviour / barrier / density parameters and density bumps. Any thread (a GUI
callback, the portal, a test) may call them. Each call checks its values first (a bad one raises,
naming it, and changes nothing), then changes the operator's state under the loop's lock and queues
one typed event (:mod:`swarmdeck.console.runtime.operator_events`). At the start of every tick
:meth:`OperatorCommands.begin_tick` takes, under the same lock, the state the tick runs with
(:class:`TickSettings`) and the events queued since the last tick, stamped with this tick: so every
command takes effect exactly at the start of the next tick, and the stamp says which one. Bumps too: the
tick sees the bumps as they were at its start (``ConsoleDensity.freeze``).

:meth:`OperatorCommands.apply` replays a recorded event (re-simulation).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from swarmdeck.console.runtime import operator_events as ev
from swarmdeck.console.runtime.behaviours import Behaviour, BehaviourError, HasBarrierSettings, make_behaviour
from swarmdeck.console.runtime.coverage_worker import use_worker
from swarmdeck.console.runtime.density import BumpSet, ConsoleDensity
from swarmdeck.console.runtime.notices import Notices
from swarmdeck.console.runtime.params import BehaviourParams, DensityParams, LoopConfig, SafetyParams
from swarmdeck.core.bounds import Bounds
from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.core.ports import Closeable
from swarmdeck.devices.pipeline import barrier_filter
from swarmdeck.safety.guard import GuardConfig

OperatorListener = Callable[[tuple[ev.Stamped, ...]], None]


@dataclass(frozen=True)
class TickSettings:
    """What one tick runs with, taken at its start (:meth:`OperatorCommands.begin_tick`).

    ``filt``/``hard``: the barrier and the guard's walls-only layer (None without a guard); ``active``: the
    robots move this tick; ``events``: the operator's actions that take effect with this tick."""

    behaviour: Behaviour
    behaviour_params: BehaviourParams
    safety: SafetyParams
    density: DensityParams
    filt: Any
    hard: Any
    estop: bool
    active: bool
    run_state: str
    events: tuple[ev.Stamped, ...]


def shown(value: Any) -> str:
    """A parameter value as an event line shows it: numbers to 2 decimals (``(0.82, -0.4)``, not 17 digits)."""
    if isinstance(value, float):
        return f"{round(value, 2):g}"
    if isinstance(value, (tuple, list, np.ndarray)):
        return "(" + ", ".join(shown(v) for v in value) + ")"
    return str(value)


def close_behaviour(b: Behaviour) -> None:
    """Release what a replaced behaviour holds (a script's worker thread, once idle)."""
    if isinstance(b, Closeable):
        b.close()


class OperatorCommands:
    """The operator's state and commands (module docstring). ``run_time()``: the loop's behaviour time, s."""

    def __init__(self, config: LoopConfig, robot: GritsBotParams, guard: GuardConfig | None, notices: Notices,
                 run_time: Callable[[], float]) -> None:
        self.config, self.robot, self.guard, self.notices = config, robot, guard, notices
        self._lock = notices.lock
        self._run_time_of = run_time
        self.bumps = BumpSet()
        self.density = ConsoleDensity(config.density, self.bumps)
        self._behaviour_params = config.behaviour_params
        self._safety_params = config.safety
        self._behaviour: Behaviour = self._make_behaviour(config.behaviour, config.behaviour_params, config.safety)
        self._filter = self._make_filter(config.safety)
        self._hard_filter = self._make_filter(config.safety, pairs=False) if guard is not None else None
        self._operator_safety: SafetyParams | None = None  # kept while a behaviour runs its own barrier gains
        self._barrier_keys: set[str] = set()  # which of them behaviours changed
        self._state = "running"
        self._estop = False
        self._steps = 0
        self._pending: list[ev.OperatorEvent] = []
        self._operator_listeners: list[OperatorListener] = []

    # ------------------------------------------------------------------ construction helpers
    def _make_behaviour(self, name: str, params: BehaviourParams, safety: SafetyParams) -> Behaviour:
        return make_behaviour(name, params, self.config.bounds, self.config.max_speed, safety.safety_distance,
                              script_budget=self.config.script_budget_s,
                              coverage_worker=use_worker(self.config.coverage_worker, self.config.n_robots))

    def _make_filter(self, p: SafetyParams, pairs: bool = True) -> Any:
        """The unicycle barrier: the QP on the look-ahead points plus each robot's four wheel-limit
        rows, so the certified command is one the wheels can execute (no saturation afterwards).
        ``pairs`` False: walls and obstacles only (the guard's hard layer)."""
        cfg = self.config
        return barrier_filter(self.robot, cfg.bounds, cfg.dt, safety_distance=p.safety_distance, gamma=p.gamma,
                              class_k=p.class_k, max_speed=cfg.max_speed, mode=p.mode, pairs=pairs,
                              **({} if cfg.obstacles is None else {"obstacles": cfg.obstacles}))

    def _queue(self, event: ev.OperatorEvent) -> None:
        with self._lock:
            self._pending.append(event)

    # ------------------------------------------------------------------ state
    @property
    def run_state(self) -> str:
        """``"running"``, ``"paused"`` or ``"estop"``."""
        return "estop" if self._estop else self._state

    @property
    def behaviour_name(self) -> str:
        return self._behaviour.name

    @property
    def behaviour_params(self) -> BehaviourParams:
        return self._behaviour_params

    @property
    def safety_params(self) -> SafetyParams:
        return self._safety_params

    @property
    def pending_steps(self) -> int:
        """Ticks with motion still to run after :meth:`step` (0 when none)."""
        return self._steps

    def subscribe_operator(self, listener: OperatorListener) -> Callable[[], None]:
        """Call ``listener(events)`` on the loop thread at the start of every tick that takes operator
        events (each :class:`~swarmdeck.console.runtime.operator_events.Stamped`); returns an unsubscribe."""
        with self._lock:
            self._operator_listeners.append(listener)

        def unsubscribe() -> None:
            with self._lock:
                if listener in self._operator_listeners:
                    self._operator_listeners.remove(listener)

        return unsubscribe

    def begin_tick(self, tick: int, now: float) -> TickSettings:
        """The state tick ``tick`` (loop clock ``now``, s) runs with, and the events that take effect with it."""
        with self._lock:
            stamped = tuple(ev.Stamped(tick, now, e) for e in self._pending)
            self._pending.clear()
            active = not self._estop and (self._state == "running" or self._steps > 0)
            if active and self._state != "running":
                self._steps -= 1
            self.density.freeze(self._run_time_of())
            return TickSettings(self._behaviour, self._behaviour_params, self._safety_params, self.density.params,
                                self._filter, self._hard_filter, self._estop, active, self.run_state, stamped)

    def tell_operator_listeners(self, events: tuple[ev.Stamped, ...]) -> None:
        """Hand a tick's operator events to the listeners (a failing one is counted and reported)."""
        if not events:
            return
        with self._lock:
            listeners = list(self._operator_listeners)
        for listener in listeners:
            try:
                listener(events)
            except Exception as exc:
                self.notices.count("listener")
                self.notices.post(f"operator event listener failed: {type(exc).__name__}: {exc}")

    # ------------------------------------------------------------------ run state
    def run(self) -> None:
        """Resume (ignored while the emergency stop is engaged)."""
        with self._lock:
            if self._estop:
                self.notices.post("run ignored: release the emergency stop first")
                return
            self._state = "running"
            self._queue(ev.Run())

    def pause(self) -> None:
        """Robots hold still (a simulation stops advancing) until :meth:`run` or :meth:`step`."""
        with self._lock:
            self._state = "paused"
            self._queue(ev.Pause())

    def step(self, n: int = 1) -> None:
        """While paused: run exactly ``n`` more ticks with motion."""
        with self._lock:
            if self._estop:
                self.notices.post("step ignored: release the emergency stop first")
                return
            self._state = "paused"
            self._steps += int(n)
            self._queue(ev.Step(int(n)))

    def estop(self) -> None:
        """Emergency stop: every command of the next tick (and after) is zero."""
        with self._lock:
            if not self._estop:
                self._estop = True
                self._steps = 0
                self.notices.post("EMERGENCY STOP")
                self._queue(ev.EStop())

    def release(self) -> None:
        """Release the emergency stop; the loop stays paused until :meth:`run`."""
        with self._lock:
            if self._estop:
                self._estop = False
                self._state = "paused"
                self.notices.post("emergency stop released (paused)")
                self._queue(ev.Release())

    # ------------------------------------------------------------------ behaviour and parameters
    def set_behaviour(self, name: str) -> None:
        """Switch behaviour; raises BehaviourError (nothing changes) for an unknown name or a bad script."""
        self.use_behaviour(self._make_behaviour(name, self._behaviour_params, self._safety_params))

    def use_behaviour(self, b: Behaviour) -> None:
        """Switch to a ready-made behaviour object (e.g. the portal's sandboxed-script commands, the
        fleet's set-up and return maneuvers of :mod:`swarmdeck.console.runtime.fleet_upkeep`) from the
        next tick on, through the same barrier pipeline; the one it replaces is closed. A behaviour
        with a ``barrier`` mapping (e.g. ``{"class_k": "linear", "gamma": 20.0}``: the gains its
        maneuvers are made for) runs with those barrier settings; the operator's come back with the
        next behaviour."""
        with self._lock:
            old, self._behaviour = self._behaviour, b
            self.notices.alert("behaviour", None)
            self.notices.post(f"behaviour: {b.name}")
            self._queue(ev.SwitchBehaviour(b.name))
        self._behaviour_barrier(b.barrier if isinstance(b, HasBarrierSettings) else None)
        if old is not b:
            close_behaviour(old)

    def _behaviour_barrier(self, barrier: Any) -> None:
        """Apply a behaviour's own barrier settings (keeping the operator's), or restore the operator's
        values of what behaviours changed. Not operator events: replaying the behaviour switch does it again."""
        if barrier:
            if self._operator_safety is None:
                self._operator_safety = self._safety_params
            self._barrier_keys |= set(barrier)
            self._set_safety(dict(barrier), record=False)
        elif self._operator_safety is not None:
            saved, self._operator_safety = self._operator_safety, None
            keys, self._barrier_keys = sorted(self._barrier_keys), set()
            self._set_safety({k: getattr(saved, k) for k in keys}, record=False)

    def set_params(self, **changes: Any) -> BehaviourParams:
        """Change behaviour parameters (see BehaviourParams); BehaviourError/ValueError for bad values."""
        try:
            params = replace(self._behaviour_params, **changes)
        except TypeError as exc:
            raise BehaviourError(str(exc)) from None
        name = self._behaviour.name
        b = self._make_behaviour(name, params, self._safety_params) if not name.startswith("script:") else self._behaviour
        with self._lock:
            self._behaviour_params = params
            old, self._behaviour = self._behaviour, b
            self.notices.post("parameters: " + ", ".join(f"{k}={shown(v)}" for k, v in changes.items()))
            self._queue(ev.SetParams(ev.changes_of(params, changes)))
        if old is not b:
            close_behaviour(old)  # a coverage worker's thread
        return params

    def set_safety(self, **changes: Any) -> SafetyParams:
        """Change the barrier (enabled, safety_distance, gamma, class_k, mode); ValueError for bad values."""
        return self._set_safety(changes, record=True)

    def _set_safety(self, changes: dict[str, Any], record: bool) -> SafetyParams:
        try:
            params = replace(self._safety_params, **changes)
        except TypeError as exc:
            raise ValueError(str(exc)) from None
        filt = self._make_filter(params)
        hard = self._make_filter(params, pairs=False) if self.guard is not None else None
        with self._lock:
            rebuild = params.safety_distance != self._safety_params.safety_distance
            self._safety_params = params
            self._filter, self._hard_filter = filt, hard
            if rebuild and self._behaviour.name == "coverage":
                old, self._behaviour = self._behaviour, self._make_behaviour("coverage", self._behaviour_params, params)
                close_behaviour(old)  # a coverage worker's thread
            self.notices.post("safety: " + ", ".join(f"{k}={shown(v)}" for k, v in changes.items()))
            if not params.enabled:
                self.notices.post("WARNING: safety barrier OFF" if self.guard is None else
                                  f"safety barrier OFF, guard on: walls and docked robots stay hard; the barrier "
                                  f"comes back if a pair would come closer than {self.guard.guard_distance:g} m or "
                                  f"it would intervene by more than {self.guard.max_intervention:g} m/s")
            if record:
                self._queue(ev.SetSafety(ev.changes_of(params, changes)))
        return params

    def barrier_back_on(self) -> None:
        """The guard revoked a bypass: the barrier is on again (the loop's own act, not an operator event)."""
        with self._lock:
            self._safety_params = replace(self._safety_params, enabled=True)

    def set_density(self, **changes: Any) -> DensityParams:
        """Change the density parameters (see DensityParams); ValueError for bad values."""
        try:
            params = replace(self.density.params, **changes)
        except TypeError as exc:
            raise ValueError(str(exc)) from None
        with self._lock:
            self.density.params = params
            self._queue(ev.SetDensity(ev.changes_of(params, changes)))
        return params

    def set_moving_density(self, on: bool) -> None:
        """Switch the circling bump on or off."""
        self.set_density(moving=bool(on))

    # ------------------------------------------------------------------ bumps
    def add_bump(self, xy: Any, sigma: float | None = None, weight: float | None = None) -> int:
        """Add a density bump at ``xy`` (m); returns its id. ValueError for bad values."""
        x0, x1, y0, y1 = self.config.bounds
        p = np.asarray(xy, dtype=float).reshape(-1)[:2]
        if not (x0 <= p[0] <= x1 and y0 <= p[1] <= y1):
            raise ValueError(f"bump centre ({p[0]:.3f}, {p[1]:.3f}) m is outside the arena {self.config.bounds}")
        d = self.density.params
        s, w = d.bump_sigma if sigma is None else float(sigma), d.bump_weight if weight is None else float(weight)
        with self._lock:
            t = self._run_time_of()
            bid = self.bumps.add(p, s, w, t)
            self._queue(ev.AddBump(bid, float(p[0]), float(p[1]), s, w, t))
            self.notices.post(f"bump {bid} added at ({p[0]:.2f}, {p[1]:.2f})")
        return bid

    def move_bump(self, bid: int, xy: Any) -> None:
        """Drag bump ``bid`` to ``xy`` (m; kept inside the arena)."""
        p = Bounds.of(self.config.bounds).clip(np.asarray(xy, dtype=float).reshape(-1)[:2])
        with self._lock:
            t = self._run_time_of()
            self.bumps.move(bid, p, t)
            self._queue(ev.MoveBump(int(bid), float(p[0]), float(p[1]), t))

    def update_bump(self, bid: int, sigma: float | None = None, weight: float | None = None) -> None:
        """Change bump ``bid``'s σ (m) and/or weight; ValueError for bad values or an unknown bump."""
        with self._lock:
            self.bumps.update(bid, sigma, weight)
            self._queue(ev.UpdateBump(int(bid), None if sigma is None else float(sigma),
                                      None if weight is None else float(weight)))

    def remove_bump(self, bid: int) -> None:
        """Fade bump ``bid`` out."""
        with self._lock:
            t = self._run_time_of()
            self.bumps.remove(bid, t)
            self._queue(ev.RemoveBump(int(bid), t))
            self.notices.post(f"bump {bid} removed")

    # ------------------------------------------------------------------ replay
    def apply(self, event: ev.OperatorEvent) -> None:
        """Do what a recorded event did (re-simulation): the same command, bumps at their recorded times.
        ValueError/BehaviourError when it cannot be done here (e.g. a script that is not on this machine)."""
        match event:
            case ev.Run():
                self.run()
            case ev.Pause():
                self.pause()
            case ev.Step(n=n):
                self.step(n)
            case ev.EStop():
                self.estop()
            case ev.Release():
                self.release()
            case ev.SwitchBehaviour(name=name):
                self.set_behaviour(name)
            case ev.SetParams():
                self.set_params(**event.as_kwargs())
            case ev.SetSafety():
                self.set_safety(**event.as_kwargs())
            case ev.SetDensity():
                self.set_density(**event.as_kwargs())
            case ev.AddBump():
                with self._lock:
                    bid = self.bumps.add((event.x, event.y), event.sigma, event.weight, event.t)
                    if bid != event.bid:
                        raise ValueError(f"replayed bump got id {bid}, recorded {event.bid}")
                    self._queue(event)
            case ev.MoveBump():
                with self._lock:
                    self.bumps.move(event.bid, (event.x, event.y), event.t)
                    self._queue(event)
            case ev.UpdateBump():
                self.update_bump(event.bid, event.sigma, event.weight)
            case ev.RemoveBump():
                with self._lock:
                    self.bumps.remove(event.bid, event.t)
                    self._queue(event)
            case _:
                raise ValueError(f"not an operator event: {event!r}")

