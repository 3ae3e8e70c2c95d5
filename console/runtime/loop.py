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

One error policy covers every stage (:meth:`ControlLoop._stage`): a stage that
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
the loop paused).
"""
from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from swarmdeck.console.runtime.batteries import BatteryWatch, low_battery_alert
from swarmdeck.console.runtime.behaviours import (
    Behaviour,
    BehaviourError,
    BehaviourParams,
    HasBarrierSettings,
    HoldsRobots,
    ReportsHealth,
    TickInput,
    goal_params,
    make_behaviour,
)
from swarmdeck.console.runtime.contacts import ContactWatch
from swarmdeck.console.runtime.density import BumpSet
from swarmdeck.console.runtime.frame import BarrierFrame, ContactsFrame, CoverageFrame, Frame
from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.checks import in_range, require_in_range
from swarmdeck.core.kinematics import GritsBotParams, lookahead_points, saturate
from swarmdeck.core.ports import (
    Closeable,
    CommandSink,
    PoseSource,
    ProvidesImage,
    SensedPoses,
    close_ports,
    obstacles_of,
)
from swarmdeck.coverage.densities import s1_density
from swarmdeck.coverage.density import GaussianMixture, merge_mixtures
from swarmdeck.devices import ArenaConfig
from swarmdeck.devices.clock import RealTimePacer
from swarmdeck.devices.pipeline import Certified, barrier_filter, brake, certify, certify_bypassed
from swarmdeck.devices.simulated_robots import SimulatedRobots
from swarmdeck.safety.guard import GuardCheck, GuardConfig

FrameListener = Callable[[Frame], None]


@dataclass(frozen=True)
class SafetyParams:
    """The barrier filter as the operator sets it: on/off, D_s (m, 0.11–0.4), γ (1–1000), class-K, and
    ``mode``: "centralised", "distributed" or "auto" (distributed above 200 robots; ``swarmdeck.safety``)."""

    enabled: bool = True
    safety_distance: float = 0.17
    gamma: float = 100.0
    class_k: str = "cubic"
    mode: str = "auto"

    def __post_init__(self) -> None:
        require_in_range(self.safety_distance, "safety_distance (D_s)", 0.11, 0.4, unit="m")
        require_in_range(self.gamma, "gamma", 1.0, 1000.0)
        if self.class_k not in ("cubic", "linear"):
            raise ValueError(f"class_k must be 'cubic' or 'linear', got {self.class_k!r}")
        if self.mode not in ("centralised", "distributed", "auto"):
            raise ValueError(f"mode must be 'centralised', 'distributed' or 'auto', got {self.mode!r}")


@dataclass(frozen=True)
class DensityParams:
    """The console's density: an optional circling bump (REFERENCE.md §5 S1) and defaults for new bumps."""

    moving: bool = True
    radius: float = 0.6
    period: float = 20.0
    sigma: float = 0.4
    weight: float = 1.0
    floor: float = 0.05
    bump_sigma: float = 0.25
    bump_weight: float = 1.0

    def __post_init__(self) -> None:
        s1_density(self.radius, self.period, self.sigma, self.weight, self.floor)  # validates
        if not in_range(self.floor, 0.0, lo_open=True):
            raise ValueError(f"density floor must be > 0 (keeps every cell's mass positive), got {self.floor!r}")
        require_in_range(self.bump_sigma, "bump_sigma", 0.05, 1.0, unit="m")
        require_in_range(self.bump_weight, "bump_weight", 0.0, 5.0)


@dataclass(frozen=True)
class LoopConfig:
    """Everything the loop starts with. Units m, s."""

    n_robots: int = 12
    dt: float = 0.033
    bounds: Bounds = DEFAULT_BOUNDS
    seed: int | None = None
    behaviour: str = "coverage"
    max_speed: float = 0.2
    behaviour_params: BehaviourParams = field(default_factory=BehaviourParams)
    safety: SafetyParams = field(default_factory=SafetyParams)
    density: DensityParams = field(default_factory=DensityParams)
    script_budget: float | None = None

    @property
    def script_budget_s(self) -> float:
        """How long a tick waits for a ``script:`` behaviour, s: ``script_budget``, or half of ``dt``
        (the other half is the loop's own work). A script that takes longer is abandoned for the tick
        (robots stopped; :mod:`swarmdeck.console.runtime.deadline`)."""
        return 0.5 * self.dt if self.script_budget is None else float(self.script_budget)

    def __post_init__(self) -> None:
        # no upper bound here: how many fit depends on the arena (the initial layout names the maximum)
        require_in_range(self.n_robots, "n_robots", 1, integer=True)
        require_in_range(self.dt, "dt", 0.005, 0.5, unit="s")
        require_in_range(self.max_speed, "max_speed", 0.0, 1.0, unit="m/s", lo_open=True)
        ArenaConfig(bounds=self.bounds, dt=self.dt)  # validates bounds
        b = self.script_budget
        if b is not None and (isinstance(b, bool) or not isinstance(b, (int, float)) or not 0 < b <= 0.5):
            raise ValueError(f"script_budget must be in (0, 0.5] s, got {b!r}")


class ConsoleDensity:
    """The one density the behaviours see: circling bump + browser bumps + input contacts (a Density).

    ``at(t)`` takes the loop's run time; the contact part is the snapshot the loop
    set for this tick (contacts live on the loop clock).
    """

    def __init__(self, params: DensityParams, bumps: BumpSet) -> None:
        self.params = params
        self.moving = s1_density(params.radius, params.period, params.sigma, params.weight, params.floor)
        self.bumps = bumps
        self.contacts: GaussianMixture | None = None
        self._cache: tuple[Any, GaussianMixture] | None = None
        self._cache_contacts: GaussianMixture | None = None

    def at(self, t: float) -> GaussianMixture:
        key = (t, self.bumps.revision, self.params)
        if self._cache is not None and self._cache[0] == key and self._cache_contacts is self.contacts:
            return self._cache[1]
        parts = [self.moving.at(t) if self.params.moving else None, self.bumps.snapshot(t, self.params.floor),
                 self.contacts]
        snap = merge_mixtures(parts, self.params.floor)
        self._cache, self._cache_contacts = (key, snap), self.contacts
        return snap


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
    return SensedPoses(ids, poses, seen, **extra)


def _shown(value: Any) -> str:
    """A parameter value as an event line shows it: numbers to 2 decimals (``(0.82, -0.4)``, not 17 digits)."""
    if isinstance(value, float):
        return f"{round(value, 2):g}"
    if isinstance(value, (tuple, list, np.ndarray)):
        return "(" + ", ".join(_shown(v) for v in value) + ")"
    return str(value)


def _close_behaviour(b: Behaviour) -> None:
    """Release what a replaced behaviour holds (a script's worker thread, once idle)."""
    if isinstance(b, Closeable):
        b.close()


class _Stage:
    """One stage's outcome under the loop's error policy (:meth:`ControlLoop._stage`)."""

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
    d, _ = cKDTree(points).query(points, k=2)
    return float(d[:, 1].min())


class ControlLoop:
    """The console's control loop. See the module docstring.

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
        self.config = config if config is not None else LoopConfig()
        cfg = self.config
        self.robot = robot if robot is not None else GritsBotParams()
        if source is None or sink is None:
            sim = SimulatedRobots(cfg.n_robots, ArenaConfig(bounds=cfg.bounds, dt=cfg.dt, seed=cfg.seed), self.robot)
            source = source if source is not None else sim
            sink = sink if sink is not None else sim
        self.source, self.sink = source, sink
        self.inputs = inputs
        if inputs is not None and contact_density is None:
            from swarmdeck.inputs import ContactDensity

            contact_density = ContactDensity()
        self.contact_density = contact_density
        self._clock = clock
        self._lock = threading.RLock()
        self.bumps = BumpSet()
        self.density = ConsoleDensity(cfg.density, self.bumps)
        self._behaviour_params = cfg.behaviour_params
        self._safety_params = cfg.safety
        self._behaviour: Behaviour = self._make_behaviour(cfg.behaviour, cfg.behaviour_params, cfg.safety)
        self._filter = self._make_filter(cfg.safety)
        self.guard = guard
        self._hard_filter = self._make_filter(cfg.safety, pairs=False) if guard is not None else None
        self._braking = False  # from the first bypassed tick on, the guard's brake holds
        self.revocations: list[dict[str, Any]] = []  # each time the guard switched the barrier back on
        self.brakes = 0  # ticks on which the guard's brake stopped robots
        self.contacts = ContactWatch()
        self._state = "running"
        self._estop = False
        self._steps = 0
        self._tick = 0
        self._run_time = 0.0
        self._time_origin: float | None = None
        self._alerts: dict[str, str] = {}
        self._events: list[str] = []
        self._listeners: list[FrameListener] = []
        self._health_fns: dict[str, Callable[[], str]] = {}
        self.errors: dict[str, int] = {}
        self.latest: Frame | None = None
        self._last_sensed: SensedPoses | None = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self.overruns = 0
        self.battery_watch = BatteryWatch()
        self._operator_safety: SafetyParams | None = None  # kept while a behaviour runs its own barrier gains

    # ------------------------------------------------------------------ construction helpers
    def _make_behaviour(self, name: str, params: BehaviourParams, safety: SafetyParams) -> Behaviour:
        return make_behaviour(name, params, self.config.bounds, self.config.max_speed, safety.safety_distance,
                              script_budget=self.config.script_budget_s)

    def _make_filter(self, p: SafetyParams, pairs: bool = True) -> Any:
        """The unicycle barrier: the QP on the look-ahead points plus each robot's four wheel-limit
        rows, so the certified command is one the wheels can execute (no saturation afterwards).
        ``pairs`` False: walls and obstacles only (the guard's hard layer)."""
        cfg = self.config
        return barrier_filter(self.robot, cfg.bounds, cfg.dt, safety_distance=p.safety_distance, gamma=p.gamma,
                              class_k=p.class_k, max_speed=cfg.max_speed, mode=p.mode, pairs=pairs)

    # ------------------------------------------------------------------ operator commands (thread-safe)
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
    def run_time(self) -> float:
        """Behaviour time, s: advances by dt only on ticks with motion."""
        return self._run_time

    @property
    def time_origin(self) -> float | None:
        """The loop clock at the first tick (``Frame.time`` of the first Frame), s; None before it.
        Session time = ``Frame.time − time_origin`` (see the module docstring, "Clocks")."""
        return self._time_origin

    @property
    def pending_steps(self) -> int:
        """Ticks with motion still to run after :meth:`step` (0 when none)."""
        return self._steps

    def run(self) -> None:
        """Resume (ignored while the emergency stop is engaged)."""
        with self._lock:
            if self._estop:
                self._post("run ignored: release the emergency stop first")
                return
            self._state = "running"

    def pause(self) -> None:
        """Robots hold still (a simulation stops advancing) until :meth:`run` or :meth:`step`."""
        with self._lock:
            self._state = "paused"

    def step(self, n: int = 1) -> None:
        """While paused: run exactly ``n`` more ticks with motion."""
        with self._lock:
            if self._estop:
                self._post("step ignored: release the emergency stop first")
                return
            self._state = "paused"
            self._steps += int(n)

    def estop(self) -> None:
        """Emergency stop: every command of the next tick (and after) is zero."""
        with self._lock:
            if not self._estop:
                self._estop = True
                self._steps = 0
                self._post("EMERGENCY STOP")

    def release(self) -> None:
        """Release the emergency stop; the loop stays paused until :meth:`run`."""
        with self._lock:
            if self._estop:
                self._estop = False
                self._state = "paused"
                self._post("emergency stop released (paused)")

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
            self._alerts.pop("behaviour", None)
            self._post(f"behaviour: {b.name}")
        self._behaviour_barrier(b.barrier if isinstance(b, HasBarrierSettings) else None)
        if old is not b:
            _close_behaviour(old)

    def _behaviour_barrier(self, barrier: Any) -> None:
        """Apply a behaviour's own barrier settings (keeping the operator's), or restore the operator's."""
        if barrier:
            if self._operator_safety is None:
                self._operator_safety = self._safety_params
            self.set_safety(**dict(barrier))
        elif self._operator_safety is not None:
            saved, self._operator_safety = self._operator_safety, None
            self.set_safety(class_k=saved.class_k, gamma=saved.gamma, safety_distance=saved.safety_distance)

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
            self._behaviour = b
            self._post("parameters: " + ", ".join(f"{k}={_shown(v)}" for k, v in changes.items()))
        return params

    def set_safety(self, **changes: Any) -> SafetyParams:
        """Change the barrier (enabled, safety_distance, gamma, class_k); ValueError for bad values."""
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
                self._behaviour = self._make_behaviour("coverage", self._behaviour_params, params)
            self._post("safety: " + ", ".join(f"{k}={_shown(v)}" for k, v in changes.items()))
            if not params.enabled:
                self._post("WARNING: safety barrier OFF" if self.guard is None else
                           f"safety barrier OFF, guard on: walls and docked robots stay hard; the barrier comes "
                           f"back if a pair would come closer than {self.guard.guard_distance:g} m or it would "
                           f"intervene by more than {self.guard.max_intervention:g} m/s")
        return params

    def set_moving_density(self, on: bool) -> None:
        with self._lock:
            self.density.params = replace(self.density.params, moving=bool(on))

    def add_bump(self, xy: Any, sigma: float | None = None, weight: float | None = None) -> int:
        """Add a density bump at ``xy`` (m); returns its id. ValueError for bad values."""
        x0, x1, y0, y1 = self.config.bounds
        p = np.asarray(xy, dtype=float).reshape(-1)[:2]
        if not (x0 <= p[0] <= x1 and y0 <= p[1] <= y1):
            raise ValueError(f"bump centre ({p[0]:.3f}, {p[1]:.3f}) m is outside the arena {self.config.bounds}")
        d = self.density.params
        bid = self.bumps.add(p, d.bump_sigma if sigma is None else sigma, d.bump_weight if weight is None else weight,
                             self._run_time)
        self.post(f"bump {bid} added at ({p[0]:.2f}, {p[1]:.2f})")
        return bid

    def move_bump(self, bid: int, xy: Any) -> None:
        x0, x1, y0, y1 = self.config.bounds
        p = np.asarray(xy, dtype=float).reshape(-1)[:2]
        self.bumps.move(bid, np.clip(p, [x0, y0], [x1, y1]), self._run_time)

    def update_bump(self, bid: int, sigma: float | None = None, weight: float | None = None) -> None:
        self.bumps.update(bid, sigma, weight)

    def remove_bump(self, bid: int) -> None:
        self.bumps.remove(bid, self._run_time)
        self.post(f"bump {bid} removed")

    def post(self, message: str) -> None:
        """Add a message to the next Frame's events (thread-safe)."""
        with self._lock:
            self._post(message)

    def _post(self, message: str) -> None:
        self._events.append(str(message))

    def add_health(self, name: str, fn: Callable[[], str]) -> None:
        """Show ``fn()`` under ``name`` in every Frame's ``health`` (e.g. the recorder's state)."""
        with self._lock:
            self._health_fns[str(name)] = fn

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
    def _count(self, what: str) -> None:
        self.errors[what] = self.errors.get(what, 0) + 1

    def _alert(self, key: str, message: str | None, event: bool = True) -> None:
        if message is None:
            self._alerts.pop(key, None)
        elif self._alerts.get(key) != message:
            self._alerts[key] = message
            if event:
                self._events.append(message)

    @contextmanager
    def _stage(self, key: str, failure: str, *, stops: bool = True) -> Iterator[_Stage]:
        """The tick's one error policy, around one stage.

        If the stage raises: count it under ``errors[key]``, raise the alert ``key`` as
        "<failure>: <Type>: <message>[; robots stopped]", keep the stage's stopped defaults and
        (``stops``) send zero to every robot this tick; the loop keeps running. Otherwise the
        alert ``key`` shows what the stage :meth:`_Stage.warn`-ed, or is cleared.
        """
        stage = _Stage()
        try:
            yield stage
        except Exception as exc:  # a failing stage stops the robots, tells, and the loop keeps running
            stage.failed, stage.error = True, exc
            self._count(key)
            message: str | None = f"{failure}: {type(exc).__name__}: {exc}" + ("; robots stopped" if stops else "")
        else:
            if stage.counted:
                self._count(key)
            message = stage.alert
        with self._lock:
            self._alert(key, message)

    def tick(self) -> Frame:
        """Run one tick now and return its Frame (virtual clock unless a clock was given).

        The stages of the module docstring, each under :meth:`_stage` (the one error policy).
        """
        marks = [time.perf_counter()]
        with self._lock:
            behaviour, filt, sp, estop = self._behaviour, self._filter, self._safety_params, self._estop
            hard = self._hard_filter
            active = not estop and (self._state == "running" or self._steps > 0)
            if active and self._state != "running":
                self._steps -= 1
            run_state, density_params = self.run_state, self.density.params
        now = self._clock() if self._clock is not None else self._tick * self.config.dt
        if self._time_origin is None:
            self._time_origin = now

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
        health, contacts, mixture, snapshot = self._health(), ContactsFrame(), None, None
        if self.inputs is not None:
            with self._stage("inputs", "inputs failed", stops=False):
                contacts, mixture = self._poll_inputs(now, health)
            self.density.contacts = mixture
        with self._stage("density", "density failed", stops=False):
            snapshot = self.density.at(self._run_time)
        marks.append(time.perf_counter())

        # 3. control: the behaviour's nominal look-ahead velocities, within max_speed
        nominal, coverage, movable = np.zeros((n, 2)), None, seen
        with self._stage("behaviour", f"{behaviour.name} failed") as control:
            nominal, coverage = self._control(behaviour, control, poses, points, ids, seen)
            if isinstance(behaviour, HoldsRobots):  # robots the behaviour holds in place: fixed obstacles of the barrier
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
            if sp.enabled and self._braking and self.guard is not None and cert is not None:
                cert = self._brake(cert, poses, movable)  # after a bypass (a guarded tick brakes by itself)
            if sp.enabled:
                with self._lock:
                    self._alert("guard", None)  # the barrier is on: nothing for the guard to watch
        if cert is None or not active or sense.failed or control.failed:
            v, w, safe = np.zeros(n), np.zeros(n), np.zeros((n, 2))
        else:
            v, w, safe = cert.v, cert.w, (cert.safe if sp.enabled or self._braking else nominal.copy())
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

        # 6. the Frame, to every subscriber
        frame = self._frame(now, sensed, points, nominal, safe, v, w, barrier, coverage, snapshot, contacts,
                            behaviour.name, run_state, sp, density_params, health, marks)
        self._tick += 1
        if active:
            self._run_time += self.config.dt
        self.latest = frame
        self._publish(frame)
        return frame

    # ------------------------------------------------------------------ the stages' bodies
    def _sense(self, now: float) -> SensedPoses:
        sensed = _checked(self.source.read(now))
        self._last_sensed = sensed
        return sensed

    def _nobody_seen(self, error: Exception | None) -> SensedPoses:
        """The last poses with nobody seen (robots get zero); re-raises ``error`` before any reading."""
        prev = self._last_sensed
        if prev is None:
            assert error is not None
            raise error
        return replace(prev, seen=np.zeros(len(prev.ids), dtype=bool))

    def _health(self) -> dict[str, str]:
        """One line per port and per registered health function (a failing one shows its error)."""
        with self._lock:
            fns = [("robots", self.source.health)]
            if isinstance(self._behaviour, ReportsHealth):  # a script's worker, a fleet maneuver's progress
                name = self._behaviour.name
                fns.append(("script" if name.startswith("script:") else name, self._behaviour.health))
            if self.source is not self.sink:
                fns.append(("commands", self.sink.health))
            fns += list(self._health_fns.items())
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

    def _control(self, behaviour: Behaviour, stage: _Stage, poses: NDArray[np.float64], points: NDArray[np.float64],
                 ids: NDArray[np.int64], seen: NDArray[np.bool_]) -> tuple[NDArray[np.float64], CoverageFrame | None]:
        """The behaviour's (N, 2) velocities (non-finite rows zeroed and warned) and its coverage state."""
        n = len(ids)
        if n == 0:
            raise BehaviourError("no robots to control (none seen or all excluded)")
        raw, state = behaviour(TickInput(poses.copy(), points.copy(), self._run_time, self.density,
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
                 nominal: NDArray[np.float64], seen: NDArray[np.bool_], stage: _Stage) -> tuple[Certified, BarrierFrame]:
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
        new = self.contacts.update(self._tick, self._run_time, ids, poses, seen)
        touching = sorted(self.contacts.touching)
        with self._lock:
            for contact in new:
                self._post(contact.message())
            self._alert("contact", None if not touching else
                        "robots in contact: " + ", ".join(f"{a}–{b}" for a, b in touching[:10]), event=False)

    def _certify_guarded(self, filt: Any, hard: Any, guard: GuardConfig, sp: SafetyParams, ids: NDArray[np.int64],
                         poses: NDArray[np.float64], points: NDArray[np.float64], nominal: NDArray[np.float64],
                         seen: NDArray[np.bool_], stage: _Stage) -> tuple[Certified, BarrierFrame]:
        """A tick with the barrier off and the guard on (module docstring, stage 4)."""
        n, d_s = len(poses), sp.safety_distance
        cert, full, check, stopped = certify_bypassed(poses, nominal, self.robot, hard, filt, guard, self.config.dt,
                                                      seen=seen, obstacles=obstacles_of(self.sink),
                                                      names=ids)
        self._braking = True
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
            self._alert("guard", None if check.trip else (
                f"guard on: walls and docked robots hard; pairs watched (guard distance {guard.guard_distance:g} m, "
                f"intervention threshold {guard.max_intervention:g} m/s)"), event=False)
        return cert, barrier

    def _revoke(self, check: GuardCheck) -> None:
        """The guard tripped: the barrier is on again (until a person switches it off again), and says why."""
        entry = {"tick": self._tick, "t": round(self._run_time, 3), "why": check.reason,
                 "closest": None if check.closest == math.inf else round(check.closest, 4),
                 "intervention": round(check.intervention, 4)}
        with self._lock:
            self.revocations.append(entry)
            self._safety_params = replace(self._safety_params, enabled=True)
            self._post(f"BARRIER BACK ON: the bypass is revoked at t = {self._run_time:.2f} s: {check.reason}")
            self._alerts["revoked"] = f"barrier back on (bypass revoked at t = {self._run_time:.2f} s): {check.reason}"

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
            self._alert("brake", None if not stopped.any() else
                        f"guard: robots stopped that would come closer than {self.guard.guard_distance:g} m",
                        event=False)

    def _frame(self, now: float, sensed: SensedPoses, points: NDArray[np.float64], nominal: NDArray[np.float64],
               safe: NDArray[np.float64], v: NDArray[np.float64], w: NDArray[np.float64], barrier: BarrierFrame,
               coverage: CoverageFrame | None, snapshot: GaussianMixture | None, contacts: ContactsFrame,
               behaviour: str, run_state: str, sp: SafetyParams, density_params: DensityParams,
               health: dict[str, str], marks: list[float]) -> Frame:
        with self._lock:
            events = tuple(self._events)
            self._events.clear()
            alerts = tuple(self._alerts.values())
        bp = self._behaviour_params
        params = {
            "kappa": bp.kappa, "law": bp.law, "gain": bp.gain, "formation_edge": bp.formation_edge,
            "formation_gain": bp.formation_gain, "safety_enabled": sp.enabled, "safety_distance": sp.safety_distance,
            "gamma": sp.gamma, "class_k": sp.class_k, "barrier_mode": sp.mode, "moving_density": density_params.moving,
            "max_speed": self.config.max_speed,
        }
        if behaviour == "goto":  # the goals, for the scene's goal markers (live and in playback)
            params.update(goal_params(bp))
        timing = {name: b - a for name, a, b in zip(("sense", "inputs", "control", "safety", "actuate"),
                                                     marks, marks[1:])}
        timing["total"] = time.perf_counter() - marks[0]
        image_ref = self.source.image_ref if isinstance(self.source, ProvidesImage) else None
        return Frame(
            tick=self._tick, time=now, run_time=self._run_time, dt=self.config.dt, bounds=self.config.bounds,
            lookahead=self.robot.lookahead, poses=sensed.poses, ids=sensed.ids, seen=sensed.seen, nominal=nominal,
            safe=safe, v=v, w=w, barrier=barrier, coverage=coverage, density=snapshot, contacts=contacts,
            behaviour=behaviour, run_state=run_state, params=params, events=events, alerts=alerts, health=health,
            timing=timing, image_ref=image_ref if isinstance(image_ref, str) else None,
            is_virtual=sensed.is_virtual, battery=sensed.battery, charging=sensed.charging,
        )

    def _publish(self, frame: Frame) -> None:
        """Hand the Frame to every subscriber; a failing one is counted and reported, the rest still run."""
        with self._lock:
            listeners = list(self._listeners)
        for listener in listeners:
            try:
                listener(frame)
            except Exception as exc:
                self._count("listener")
                self.post(f"frame listener failed: {type(exc).__name__}: {exc}")

    # ------------------------------------------------------------------ threaded running
    def start(self) -> ControlLoop:
        """Run :meth:`tick` every ``dt`` seconds (monotonic clock) on a daemon thread."""
        if self._thread is not None and self._thread.is_alive():
            return self
        if self._clock is None:
            t0 = time.monotonic() - self._tick * self.config.dt
            self._clock = lambda: time.monotonic() - t0
        self._stop.clear()
        self._thread = threading.Thread(target=self._run_forever, name="swarmdeck-loop", daemon=True)
        self._thread.start()
        return self

    def _run_forever(self) -> None:
        pacer = RealTimePacer(self.config.dt)
        while not self._stop.is_set():
            try:
                self.tick()
            except Exception as exc:  # never let the thread die silently
                self._count("tick")
                self.post(f"tick failed: {type(exc).__name__}: {exc}")
                try:
                    self.sink.hold()
                except Exception:
                    self._count("sink")
            pacer.wait()
        self.overruns = pacer.overruns

    def stop(self, timeout: float = 2.0) -> None:
        """Stop the thread (robots stop: the sink is closed by :meth:`close`)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout)
            self._thread = None

    def close(self) -> None:
        """Stop the thread, stop the robots, close the sink, the inputs and the behaviour (a script's worker)."""
        self.stop()
        _close_behaviour(self._behaviour)
        try:
            close_ports(self.source, self.sink)
        finally:
            if self.inputs is not None:
                self.inputs.close()
