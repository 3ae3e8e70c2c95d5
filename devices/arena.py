"""The experiment API: program the swarm at any abstraction level of the paper (§III-C).

User code talks to one :class:`Arena` whether the robots are simulated or
real. Each step the current command — wheel speeds, unicycle ``(v, ω)``,
single-integrator velocities of the look-ahead points, go-to-goal positions or
poses, waypoint lists, or "next position" difference equations — is converted
to single-integrator velocities of the look-ahead points and handed to
:func:`~swarmdeck.devices.pipeline.certify`: the look-ahead map to ``(v, ω)``,
the wheel limits by one uniform scale per robot, the safety filter (on by
default) and fail-stop. The console's control loop calls the same function, so
an experiment and the console drive robots identically, whatever the level.

Arrays follow swarmdeck's convention: one row per robot. Commands persist
until replaced (as in rps); ``ids`` selects a subset of robots to update.
"""
from __future__ import annotations

import contextvars
import dataclasses
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.annotations import EMPTY, Annotations
from swarmdeck.core.annotator import Annotator
from swarmdeck.core.kinematics import (
    GritsBotParams,
    limit_unicycle,
    lookahead_points,
    si_to_unicycle,
    unicycle_to_si,
    wheels_to_unicycle,
)
from swarmdeck.core.obstacles import START_CLEARANCE
from swarmdeck.core.ports import SensesElsewhere, ShowsLeds
from swarmdeck.core.robot_models import DEFAULT_ROBOT_MODEL, robot_params
from swarmdeck.devices.controllers import (
    HybridPoseController,
    at_position,
    clf_unicycle_pose_controller,
    clf_unicycle_position_controller,
    si_position_controller,
)
from swarmdeck.devices.fleet.manager import FleetManager
from swarmdeck.devices.initial_conditions import random_initial_poses
from swarmdeck.devices.pipeline import CommandFilter, FilterDiagnostics, UnicycleCommandFilter, barrier_filter, certify
from swarmdeck.devices.simulated_robots import SimulatedRobots
from swarmdeck.devices.simulator import ArenaConfig, SimulatedArena, check_poses
from swarmdeck.devices.stepped import SteppedRobots
from swarmdeck.network.errors import IsolationError
from swarmdeck.sensing import SensingConfig, SensorReadings, Sensors

FloatArray = NDArray[np.float64]
GoalController = Literal["si", "clf", "pose", "hybrid"]


class ExperimentFinished(Exception):
    """Raised by :meth:`Arena.step` when the run's declared duration is over."""


@dataclass(frozen=True)
class RunDefaults:
    """Defaults a runner (``swarmdeck run``) hands to Arenas a script creates without arguments."""

    n_robots: int | None = None
    duration: float | None = None
    seed: int | None = None
    safety: bool = True
    on_create: Any = None  # callable(Arena) -> None, lets the runner find the script's arena
    on_step: Any = None  # callable(Arena) -> None after every step (progress display)
    # callable(n_robots, initial_conditions, config, params) -> robot ports (core/ports.py) for Arenas
    # built without robots (the sandbox's child: robots on the other side of a pipe); None: simulated
    backend_factory: Any = None
    # start simulated Arenas docked on the chargers and set them up first (swarmdeck run --from-docks)
    from_docks: bool = False
    # the rps facade (devices/rps/robotarium.py): rps's own semantics (the barrier only where the script
    # calls it, rps's error counts) and rps's call order (get_poses() once per step())
    rps_semantics: bool = False
    rps_call_order: bool = True
    # line-segment obstacles (core.obstacles.Obstacles) for Arenas built without their own (swarmdeck run --obstacles)
    obstacles: Any = None
    # the arena a script built without a config sees, m (None: DEFAULT_BOUNDS): its region of a shared floor
    # (devices/fleet/regions.py), so an unmodified script cannot tell it shares the floor
    bounds: Any = None

    def arena_config(self, **kw: Any) -> ArenaConfig:
        """The :class:`ArenaConfig` of an Arena (or rps Robotarium) a script builds without one: these defaults'
        seed and bounds, plus ``kw``."""
        if self.bounds is not None:
            kw.setdefault("bounds", self.bounds)
        return ArenaConfig(seed=self.seed, **kw)
    # the robot model of Arenas built without params (core/robot_models.py; None: the GRITSBot, and for the
    # rps facade the model of the script's rps generation) and that generation (devices/rps/generation.py)
    robot_model: str | None = None
    rps_generation: int | None = None


#: The sensors' noise stream beside the simulator's: Arena sensing seeds with (seed, this).
_SENSING_STREAM = 0x5E45

RUN_DEFAULTS: contextvars.ContextVar[RunDefaults] = contextvars.ContextVar("swarmdeck_run_defaults", default=RunDefaults())  # noqa: B039  (frozen)


@dataclass
class SafetyStats:
    """Running counts of the safety filter over a run."""

    calls: int = 0
    failures: int = 0
    interventions: int = 0  # robot-steps whose command the filter changed
    saturations: int = 0  # robot-steps whose command was scaled down to the wheel limits before filtering
    saturation_steps: int = 0  # steps in which at least one robot's command was scaled down
    last_status: str = "off"
    last_diagnostics: FilterDiagnostics | None = None
    failure_reasons: dict[str, int] = field(default_factory=dict)


class Arena:
    """A swarm of GRITSBots you program at the level you like.

    Args:
        number_of_robots: N. Ignored when ``initial_conditions`` is given.
        initial_conditions: ``(N, 3)`` float poses ``[x, y, θ]``; random non-overlapping when omitted.
        config: arena bounds, period, real-time pacing, seed.
        params: the robot model.
        safety: True for the default barrier filter, False to run without it, or any object
            with ``filter(points, nominal, obstacles=None)``.
        duration: declared duration, s; :meth:`step` raises :class:`ExperimentFinished` after it.
        backend: the robots to drive: robot ports (:mod:`swarmdeck.core.ports`; one object that is pose
            source and command sink, or a ``(source, sink)`` pair) — the MQTT robots
            (``devices.net.console_robots.NetworkRobots``), virtual robots beside them
            (``devices.virtual_robots.MixedRobots``), … Driven through
            :class:`~swarmdeck.devices.stepped.SteppedRobots` (:attr:`robots`). Simulated robots
            (:class:`~swarmdeck.devices.simulated_robots.SimulatedRobots`) when omitted.
        from_docks: start the simulated robots docked on the chargers and set them up to
            ``initial_conditions`` (given, or random as rps generates them) before the first step,
            as the paper's back end does (:mod:`swarmdeck.devices.fleet`); or a
            :class:`~swarmdeck.devices.fleet.manager.FleetManager` whose robots to use (its other
            robots stay docked and are obstacles for the safety filter). :attr:`fleet` is the fleet
            (None otherwise), :meth:`return_to_chargers` docks the robots after the experiment.
            Setup errors (poses outside the arena or too close, too few charged robots, a setup
            that does not finish) raise and leave the robots stopped.
        sensing: the robots' sensors (:class:`~swarmdeck.sensing.SensingConfig`: ToF distance sensors,
            range and bearing, encoders and IMU, LEDs), or None (the default: no sensors). Read them with
            :meth:`sense` after each step; set the LEDs with :meth:`set_leds`; see :meth:`use_sensors`.
        obstacles: line-segment obstacles (``(M, 2, 2)`` m, ``[[x0, y0], [x1, y1]]`` each, or an
            :class:`~swarmdeck.core.obstacles.Obstacles`; ``Obstacles.from_polygons`` for polygons):
            solid in the simulator, kept clear by the barrier (segment rows), counted as contacts by
            validation. Replaces ``config.obstacles``. Refused (ObstacleError naming the segment)
            when outside the arena or crossing a start pose.

    Example::

        arena = Arena(6)
        for _ in range(600):
            p = arena.positions()
            arena.set_velocities(-(p - p.mean(axis=0)))
            arena.step()
        print(arena.report())
    """

    def __init__(
        self,
        number_of_robots: int | None = None,
        *,
        initial_conditions: ArrayLike | None = None,
        config: ArenaConfig | None = None,
        params: GritsBotParams | None = None,
        safety: bool | CommandFilter | None = None,
        duration: float | None = None,
        backend: Any = None,
        from_docks: Any = None,
        sensing: SensingConfig | None = None,
        obstacles: Any = None,
    ) -> None:
        defaults = RUN_DEFAULTS.get()
        if from_docks is None:
            from_docks = defaults.from_docks and backend is None and defaults.backend_factory is None
        if number_of_robots is None:
            number_of_robots = defaults.n_robots
        if duration is None:
            duration = defaults.duration
        if safety is None:
            safety = defaults.safety
        if config is None:
            config = defaults.arena_config()
        if obstacles is None and config.obstacles is None:
            obstacles = defaults.obstacles
        if obstacles is not None:
            config = dataclasses.replace(config, obstacles=obstacles)  # checked inside the bounds there
        self.params = params if params is not None else robot_params(defaults.robot_model or DEFAULT_ROBOT_MODEL)
        self.config = config
        if duration is not None and not (np.isfinite(duration) and duration > 0):
            raise ValueError(f"duration must be a positive number of seconds, got {duration!r}")
        self.duration = duration
        self.fleet: Any = None
        if from_docks is not False and from_docks is not None:
            if backend is not None:
                raise ValueError("from_docks sets up simulated robots: it does not combine with a backend")
            backend = self._set_up_from_docks(from_docks, number_of_robots, initial_conditions, config)
        if backend is None:
            if number_of_robots is not None and not isinstance(number_of_robots, (int, np.integer)):
                raise ValueError(f"number_of_robots must be an integer, got {number_of_robots!r}")
            if initial_conditions is not None:
                initial_conditions = check_poses(initial_conditions)
                if config.obstacles is not None:
                    config.obstacles.check_clear(initial_conditions, START_CLEARANCE, "start pose")
            elif number_of_robots is None:
                number_of_robots = 6
            make = defaults.backend_factory if defaults.backend_factory is not None else _simulated_robots
            backend = make(number_of_robots, initial_conditions, config=config, params=self.params)
        source, sink = backend if isinstance(backend, tuple) else (backend, backend)
        self.backend = sink  # the robot ports the user handed over (or the simulated robots)
        self.robots = SteppedRobots(source, sink, params=self.params, dt=config.dt)
        self.n = int(self.robots.n_robots)
        self.ell = self.params.lookahead
        self._own_barrier = safety is True  # add_obstacles rebuilds it
        if safety is True:
            self.safety: CommandFilter | UnicycleCommandFilter | None = self._barrier()
        elif safety is False:
            self.safety = None
        else:
            if not callable(getattr(safety, "filter", None)):
                raise ValueError("safety must be True, False or an object with a filter(points, nominal) method")
            self.safety = safety
        self.safety_stats = SafetyStats()
        self.invalid_commands = 0
        self.events: deque[str] = deque(maxlen=200)  # the most recent events only: a run can be long
        self._command: tuple[str, Any] = ("si", np.zeros((self.n, 2)))
        self._hybrid = HybridPoseController(lookahead=self.ell)
        self._waypoint_index = np.zeros(self.n, dtype=int)
        self._poses_cache: FloatArray | None = None
        self.last_nominal = np.zeros((self.n, 2))
        self.last_safe = np.zeros((self.n, 2))
        self.draw = Annotator(config.bounds)
        """What the experiment draws on the arena (:class:`~swarmdeck.core.annotator.Annotator`: points, lines,
        polylines, circles, polygons, text in arena metres, with colour and lifetime): shown in the console,
        the recording, the video, the portal's live view and on the projector."""
        self.last_annotations: Annotations = EMPTY
        self._on_step = defaults.on_step
        self._annotations_read = False  # read_annotations()
        self.sensors: Sensors | None = None
        self._readings: SensorReadings | None = None
        if sensing is not None:
            self.use_sensors(sensing)
        self._sealed_for: str | None = None  # set while a decentralised controller runs (devices/decentralised.py)
        self.network: Any = None  # the robots' swarmdeck.network.Network in a decentralised run: recorded and drawn
        self.robots.start_clock()  # real robots: the run starts now, not when the robots were opened
        if defaults.on_create is not None:
            defaults.on_create(self)

    def _set_up_from_docks(self, from_docks: Any, n: int | None, initial: ArrayLike | None,
                           config: ArenaConfig) -> Any:
        """The fleet's robots set up at the start poses; their experiment view is the backend."""
        if initial is not None:
            poses = check_poses(initial)
        else:
            if n is None:
                n = 6
            if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
                raise ValueError(f"number_of_robots must be a positive integer, got {n!r}")
            poses = random_initial_poses(int(n), config.bounds, rng=config.seed)
        fleet = from_docks if isinstance(from_docks, FleetManager) else FleetManager(len(poses), config=config,
                                                                                      params=self.params)
        self.fleet = fleet
        fleet.setup(poses)
        return fleet.experiment()

    def return_to_chargers(self) -> Any:
        """Dock the robots on free charger slots after the experiment (Arenas made ``from_docks``);
        returns the fleet's :class:`~swarmdeck.devices.fleet.setup.ManeuverReport`."""
        if self.fleet is None:
            raise RuntimeError("this Arena did not start from the chargers (from_docks): there is nothing to return")
        return self.fleet.return_to_chargers()

    # ------------------------------------------------------------------ sensing
    @property
    def time(self) -> float:
        """Seconds since the start of the run."""
        return float(self.robots.time)

    @property
    def ids(self) -> NDArray[np.intp]:
        """Robot ids ``0 … N−1``."""
        return np.arange(self.n)

    @property
    def is_virtual(self) -> NDArray[np.bool_]:
        """``(N,)`` bool: robots simulated beside the physical ones (a
        :class:`~swarmdeck.devices.virtual_robots.MixedRobots`); all False otherwise. The only way
        user code can tell them apart: the safety filter treats every robot alike."""
        return self.robots.is_virtual

    def poses(self) -> FloatArray:
        """Current poses ``(N, 3)`` ``[x, y, θ]`` (a fresh copy every call)."""
        self._refuse_if_sealed("poses()")
        return self.robots.poses

    def positions(self) -> FloatArray:
        """Look-ahead points ``(N, 2)``: the points single-integrator commands move."""
        self._refuse_if_sealed("positions()")
        return lookahead_points(self.robots.poses, self.ell)

    # ------------------------------------------------------------------ obstacles declared later (issue 28.3)
    def _barrier(self) -> UnicycleCommandFilter:
        """swarmdeck's barrier for this Arena's robots, bounds, period and obstacle segments."""
        config = self.config
        return barrier_filter(self.params, config.bounds, config.dt, robots=self.n, max_speed=self.params.max_speed,
                              **({} if config.obstacles is None else {"obstacles": config.obstacles}))

    def add_obstacles(self, obstacles: Any) -> None:
        """Make these line segments (``(M, 2, 2)`` m, ``[[x0, y0], [x1, y1]]`` each, or an
        :class:`~swarmdeck.core.obstacles.Obstacles`) solid from now on, beside the Arena's own: the barrier keeps
        the robots off them (when it is swarmdeck's), the simulator blocks them, validation counts contacts, the
        sensors see them. The trusted side of a sandboxed run calls it with the obstacles the script declared (an rps
        2.x ``Robotarium(obstacles=...)``). ObstacleError (a ValueError) naming the segment when one is invalid,
        outside the arena or within START_CLEARANCE of a robot."""
        from swarmdeck.core.obstacles import Obstacles

        new = Obstacles.of(obstacles)
        if not new:
            return
        old = self.config.obstacles
        merged = new if old is None else Obstacles(np.concatenate([old.segments, new.segments]))
        config = dataclasses.replace(self.config, obstacles=merged)  # checked inside the bounds there
        merged.check_clear(self.robots.poses, START_CLEARANCE, "robot")
        self.config = config
        sim = getattr(self.backend, "sim", None)  # simulated robots (and verification's): contact, validation
        if isinstance(sim, SimulatedArena):
            sim.config = dataclasses.replace(sim.config, obstacles=merged)
        if self._own_barrier:
            self.safety = self._barrier()
        if self.sensors is not None:
            self.use_sensors(self.sensors.config, obstacles=merged.segments)

    # ------------------------------------------------------------------ the robots' own sensors (issue 28.1)
    def use_sensors(self, sensing: SensingConfig | None, *, obstacles: ArrayLike | None = None,
                    seed: int | None = None) -> Sensors | None:
        """Give the robots these sensors from now on (None: none). ``obstacles`` ``(M, 2, 2)`` m: segments the
        distance sensors see (default: the arena config's obstacle ``segments`` when it has them). The noise is seeded
        from ``seed`` (default: the arena config's seed; None: fresh entropy). Returns the
        :class:`~swarmdeck.sensing.Sensors`."""
        if isinstance(self.backend, SensesElsewhere):  # the sandbox's child: the trusted side computes the readings
            self.backend.use_sensors(sensing)
        if sensing is None:
            self.sensors, self._readings = None, None
            return None
        if obstacles is None:  # the arena's own obstacle segments (M, 2, 2), when its config has them
            obstacles = None if self.config.obstacles is None else self.config.obstacles.segments
        seed = self.config.seed if seed is None else seed
        rng = np.random.default_rng(None if seed is None else [int(seed), _SENSING_STREAM])
        self.sensors = Sensors(self.n, sensing, rng=rng, params=self.params, bounds=self.config.bounds,
                               obstacles=obstacles)
        self._readings = self.sensors.first(self.robots.poses)
        return self.sensors

    def sense(self) -> SensorReadings:
        """What the robots sensed in the last step (:class:`~swarmdeck.sensing.SensorReadings`; before the first
        step: distances NaN, encoders 0). Robots whose firmware reports readings
        (:class:`~swarmdeck.core.ports.ReportsSensors`) give theirs. RuntimeError when the Arena has no sensors."""
        if self.sensors is None or self._readings is None:
            raise RuntimeError("this Arena has no sensors: build it with Arena(..., sensing=SensingConfig(...)) "
                               "(e.g. SensingConfig(distance=DistanceSensorConfig()) for the ToF sensors)")
        return self._readings

    def set_leds(self, rgb: ArrayLike, ids: ArrayLike | None = None) -> None:
        """Set the robots' RGB LEDs: ``(N, 3)`` (or one row per id in ``ids``) of 0…255 (floats in [0, 1] are
        scaled), at once (in :meth:`sense`, the Frame, the recording and every renderer); robots with real LEDs
        (:class:`~swarmdeck.core.ports.ShowsLeds`, e.g. GRITSBots over MQTT) show them from the next command on."""
        if self.sensors is None:
            raise RuntimeError("this Arena has no sensors (and so no LEDs): build it with "
                               "Arena(..., sensing=SensingConfig())")
        self.sensors.set_leds(rgb, self._ids(ids))
        if self._readings is not None:
            self._readings = self.sensors.with_leds(self._readings)
        if isinstance(self.backend, ShowsLeds):  # robots with real LEDs: they show them too
            self.backend.set_leds(self.robots.ids, self.sensors.leds)

    def _sense_after_step(self, poses: FloatArray, v: ArrayLike, w: ArrayLike) -> None:
        """Update the readings after a step in which the robots ran ``(v, w)`` and arrived at ``poses``."""
        if self.sensors is None:
            return
        readings = None
        # isinstance(self.backend, ReportsSensors), as typing's protocol check decides it (its method present and not
        # None), without its ≈ 20 µs per step
        report = getattr(self.backend, "sensor_readings", None)
        if report is not None:
            readings = report()
        self._readings = readings if readings is not None else self.sensors.update(poses, v, w, self.config.dt)

    def _refuse_if_sealed(self, what: str) -> None:
        """IsolationError while a decentralised controller runs (:mod:`swarmdeck.devices.decentralised`)."""
        if self._sealed_for is not None:
            raise IsolationError(f"{self._sealed_for} read arena.{what}: a decentralised controller sees only its "
                                 "own view (view.pose, view.inbox, view.readings, view.state), not other robots' poses")

    # ------------------------------------------------------------------ commanding
    def _ids(self, ids: ArrayLike | None) -> NDArray[np.intp] | None:
        if ids is None:
            return None
        arr = np.atleast_1d(np.asarray(ids))
        if arr.dtype.kind not in "iu":
            raise ValueError(f"ids must be integer robot ids, got dtype {arr.dtype}")
        bad = arr[(arr < 0) | (arr >= self.n)]
        if len(bad):
            raise ValueError(f"unknown robot id(s) {bad.tolist()}: this arena has ids 0..{self.n - 1}")
        if len(np.unique(arr)) != len(arr):
            raise ValueError(f"ids must not repeat, got {arr.tolist()}")
        return arr.astype(np.intp)

    def _rows(self, name: str, values: ArrayLike, width: int | None, ids: NDArray[np.intp] | None) -> FloatArray:
        arr = np.asarray(values)
        if arr.dtype.kind not in "fiu" or arr.dtype.kind == "b":
            raise ValueError(f"{name} must be numeric, got dtype {arr.dtype}")
        rows = self.n if ids is None else len(ids)
        expected = (rows,) if width is None else (rows, width)
        if arr.shape != expected:
            raise ValueError(f"{name} must have shape {expected}, got {arr.shape}")
        return arr.astype(float, copy=True)

    def _merge(self, kind: str, full: FloatArray, ids: NDArray[np.intp] | None, part: FloatArray) -> None:
        if ids is None:
            self._command = (kind, part)
            return
        base = full.copy()
        base[ids] = part
        self._command = (kind, base)

    def _current(self, kind: str, shape: tuple[int, ...]) -> FloatArray:
        """The stored command of this kind, or zeros (robots not named in ``ids`` stand still)."""
        if self._command[0] == kind:
            return self._command[1]
        return np.zeros(shape)

    def set_wheel_speeds(self, right: ArrayLike, left: ArrayLike, ids: ArrayLike | None = None) -> None:
        """Wheel speeds ω_R, ω_L in rad/s, ``(N,)`` each (or one per id in ``ids``)."""
        sel = self._ids(ids)
        r = self._rows("right", right, None, sel)
        l = self._rows("left", left, None, sel)
        self._merge("wheels", self._current("wheels", (self.n, 2)), sel, np.column_stack((r, l)))

    def set_unicycle(self, v: ArrayLike, w: ArrayLike, ids: ArrayLike | None = None) -> None:
        """Unicycle commands: linear speed v (m/s) and turning rate ω (rad/s), ``(N,)`` each."""
        sel = self._ids(ids)
        vv = self._rows("v", v, None, sel)
        ww = self._rows("w", w, None, sel)
        self._merge("unicycle", self._current("unicycle", (self.n, 2)), sel, np.column_stack((vv, ww)))

    def set_velocities(self, velocities: ArrayLike, ids: ArrayLike | None = None) -> None:
        """Single-integrator velocities ``(N, 2)`` (m/s) of the look-ahead points."""
        sel = self._ids(ids)
        u = self._rows("velocities", velocities, 2, sel)
        self._merge("si", self._current("si", (self.n, 2)), sel, u)

    def set_next_positions(self, positions: ArrayLike, ids: ArrayLike | None = None) -> None:
        """"Next position" difference-equation commands: the look-ahead points should be at
        ``positions`` ``(N, 2)`` after one period; sent as u = (p_next − p)/dt (then made safe)."""
        sel = self._ids(ids)
        p = self._rows("positions", positions, 2, sel)
        hold = self._command[1] if self._command[0] == "next" else self.positions()
        self._merge("next", hold, sel, p)

    def set_goals(self, goals: ArrayLike, controller: GoalController = "si", ids: ArrayLike | None = None) -> None:
        """Go to goal positions ``(N, 2)`` or poses ``(N, 3)``.

        ``controller``: ``"si"`` (look-ahead point to the position, rps si position
        controller), ``"clf"`` (unicycle CLF position controller), ``"pose"`` (CLF pose
        controller; needs ``(N, 3)``), ``"hybrid"`` (approach then turn; needs ``(N, 3)``).
        """
        if controller not in ("si", "clf", "pose", "hybrid"):
            raise ValueError(f"controller must be one of 'si', 'clf', 'pose', 'hybrid', got {controller!r}")
        sel = self._ids(ids)
        g = np.asarray(goals)
        width = 3 if controller in ("pose", "hybrid") else (g.shape[-1] if g.ndim == 2 and g.shape[-1] in (2, 3) else 2)
        goals_arr = self._rows("goals", goals, width, sel)
        if not np.all(np.isfinite(goals_arr)):
            raise ValueError("goals contain NaN or inf")
        if sel is None:
            base = goals_arr
        else:
            kind, cmd = self._command
            if kind == "goals" and cmd[0] == controller and cmd[1].shape[1] == width:
                base = cmd[1].copy()
            else:  # robots not named hold where they are
                poses = self.poses()
                base = lookahead_points(poses, self.ell) if controller == "si" else poses[:, :width].copy()
            base[sel] = goals_arr
        kind, cmd = self._command
        same = kind == "goals" and cmd[0] == controller and np.array_equal(cmd[1], base)
        if not same:  # rps-style loops set the same goals every step: keep the hybrid phases then
            self._hybrid.reset()
        self._command = ("goals", (controller, base))

    def set_waypoints(self, waypoints: Sequence[ArrayLike], tolerance: float = 0.03, loop: bool = False,
                      ids: ArrayLike | None = None) -> None:
        """One list of waypoints ``(K_i, 2)`` (m) per robot, visited in order by the look-ahead point.

        A robot holds its last waypoint (or starts over when ``loop``). With ``ids``, one list
        per id: robots not named keep their waypoint lists if they had some, else hold where
        they are; ``tolerance`` (m) and ``loop`` then apply to every robot.
        """
        sel = self._ids(ids)
        named = np.arange(self.n) if sel is None else sel
        if isinstance(waypoints, (str, bytes)) or not hasattr(waypoints, "__len__"):
            raise ValueError(f"waypoints must be a sequence of (K_i, 2) arrays, one per robot, got {type(waypoints).__name__}")
        if len(waypoints) != len(named):
            raise ValueError(f"waypoints must hold one (K_i, 2) array per robot{'' if sel is None else ' in ids'} "
                             f"({len(named)}), got {len(waypoints)}")
        if not tolerance > 0:
            raise ValueError(f"tolerance must be > 0 m, got {tolerance!r}")
        lists: list[FloatArray] = [np.empty((0, 2))] * self.n
        index = np.zeros(self.n, dtype=np.intp)
        if sel is not None:  # robots not named: their current lists, or hold here
            kind, cmd = self._command
            if kind == "waypoints":
                table, lengths = cmd[0], cmd[1]
                lists = [table[i, : lengths[i]] for i in range(self.n)]  # once per call, not per tick
                index = self._waypoint_index.copy()
            else:
                here = self.positions()
                lists = [here[i : i + 1] for i in range(self.n)]
        for k, (i, wp) in enumerate(zip(named.tolist(), waypoints)):  # once per call, not per tick
            raw = np.asarray(wp)
            if raw.dtype.kind not in "fiu":
                raise ValueError(f"waypoints[{k}] must be a real (K, 2) array of metres, got dtype {raw.dtype}")
            arr = raw.astype(float)  # a copy: later changes to the caller's array do not move the robots
            if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] < 1 or not np.all(np.isfinite(arr)):
                raise ValueError(f"waypoints[{k}] must be a finite (K, 2) array with K >= 1, got shape {arr.shape}")
            lists[i] = arr
            index[i] = 0
        lengths = np.array([len(a) for a in lists], dtype=np.intp)
        table = np.empty((self.n, int(lengths.max()), 2))
        for i, arr in enumerate(lists):
            table[i, : len(arr)] = arr
            table[i, len(arr) :] = arr[-1]
        kind, cmd = self._command
        if (kind == "waypoints" and np.array_equal(cmd[1], lengths) and np.array_equal(cmd[0], table)
                and cmd[2] == float(tolerance) and cmd[3] == bool(loop)):
            index = self._waypoint_index  # the same lists again (set every step): keep each robot's progress
        self._waypoint_index = index
        self._command = ("waypoints", (table, lengths, float(tolerance), bool(loop)))

    def stop(self) -> None:
        """Command every robot to stand still."""
        self._command = ("si", np.zeros((self.n, 2)))

    @property
    def waypoint_index(self) -> NDArray[np.intp]:
        """Index of the waypoint each robot is heading to (copy)."""
        return self._waypoint_index.copy()

    # ------------------------------------------------------------------ the step
    def nominal_velocities(self, poses: FloatArray, points: FloatArray | None = None) -> FloatArray:
        """Look-ahead velocities ``(N, 2)`` the current command asks for at ``poses`` ``(N, 3)``.

        ``points``: the look-ahead points ``(N, 2)`` of ``poses`` when the caller has them already.
        """
        kind, cmd = self._command
        ell, dt = self.ell, self.config.dt
        if kind == "si":
            return cmd.copy()
        if kind == "unicycle":
            return unicycle_to_si(poses, cmd[:, 0], cmd[:, 1], ell)
        if kind == "wheels":
            v, w = wheels_to_unicycle(cmd[:, 0], cmd[:, 1], self.params)
            return unicycle_to_si(poses, v, w, ell)
        if points is None:  # the kinds below move from the look-ahead points
            points = lookahead_points(poses, ell)
        if kind == "next":
            return (cmd - points) / dt
        if kind == "goals":
            controller, goals = cmd
            if controller == "si":
                return si_position_controller(points, goals[:, :2], speed_limit=self.params.max_speed)
            if controller == "clf":
                v, w = clf_unicycle_position_controller(poses, goals)
            elif controller == "pose":
                v, w = clf_unicycle_pose_controller(poses, goals)
            else:
                v, w = self._hybrid(poses, goals)
            return unicycle_to_si(poses, v, w, ell)
        if kind == "waypoints":
            table, lengths, tol, loop = cmd
            p = points
            rows = np.arange(self.n)
            idx = self._waypoint_index
            reached = at_position(p, table[rows, idx], tol)
            advance = reached & ((idx < lengths - 1) | loop)
            idx = np.where(advance, (idx + 1) % lengths, idx)
            self._waypoint_index = idx
            return si_position_controller(p, table[rows, idx], speed_limit=self.params.max_speed)
        raise AssertionError(f"unknown command kind {kind}")  # pragma: no cover

    def step(self) -> FloatArray:
        """Advance one period: nominal → :func:`~swarmdeck.devices.pipeline.certify` (wheel limits,
        safety filter) → robots. Returns the new poses.

        Robots whose nominal command is NaN or inf are stopped for this step and the
        event counted. If the safety filter fails, every robot is stopped. Robots behind a trust
        boundary (a :class:`~swarmdeck.core.ports.NominalSink`: the sandboxed child's robots,
        console/sandbox/child.py) get the nominal ``(N, 2)`` as it is instead: the trusted side across the
        pipe certifies it.
        """
        self._refuse_if_sealed("step()")
        if self.duration is not None and self.time >= self.duration - 1e-9:
            raise ExperimentFinished(f"declared duration {self.duration} s is over")
        poses = self.robots.poses
        nominal = self.nominal_velocities(poses)
        if self.robots.nominal_sink is not None:  # robots behind a trust boundary: the far side certifies
            self.last_nominal = nominal
            self._annotate(self.time + self.config.dt)
            new_poses = self.robots.step_nominal(nominal)
            if self.sensors is not None:  # the commands the far side certified are not known here: the nominal's
                v_n, w_n = si_to_unicycle(poses, nominal, self.ell)
                self._sense_after_step(new_poses, *limit_unicycle(v_n, w_n, self.params)[:2])
            if self._on_step is not None:
                self._on_step(self)
            return new_poses
        cert = certify(poses, nominal, self.params, self.safety, obstacles=self.robots.obstacles())
        if cert.invalid.any():
            self.invalid_commands += int(cert.invalid.sum())
            self.events.append(f"t={self.time:.3f}: non-finite command for robot(s) "
                               f"{np.flatnonzero(cert.invalid).tolist()}: stopped")
        st = self.safety_stats
        st.saturations += int(cert.saturated.sum())
        st.saturation_steps += bool(cert.saturated.any())
        if self.safety is not None:
            st.calls += 1
            st.last_diagnostics, st.last_status = cert.diagnostics, cert.status
            if not cert.ok:
                st.failures += 1
                st.failure_reasons[cert.status] = st.failure_reasons.get(cert.status, 0) + 1
            else:
                st.interventions += int(np.count_nonzero(cert.changed()))
        self.last_nominal = np.where(cert.invalid[:, None], 0.0, nominal)
        self.last_safe = cert.safe
        new_poses = self.robots.step(cert.v, cert.w)
        self._sense_after_step(new_poses, cert.v, cert.w)
        self._annotate(self.time)
        if self._on_step is not None:
            self._on_step(self)
        return new_poses

    def step_unicycle(self, v: ArrayLike, w: ArrayLike) -> FloatArray:
        """Advance one period with unicycle commands ``(N,)`` [m/s], [rad/s] handed to the robots as they are
        (their own wheel limits and validation apply): the rps facade's rps semantics, where nothing but the
        script's own barrier filters. Only for an Arena without a safety filter (RuntimeError otherwise).
        Returns the new poses."""
        if self.safety is not None:
            raise RuntimeError("step_unicycle hands commands to the robots unfiltered: only for an Arena built "
                               "with safety=False")
        if self.duration is not None and self.time >= self.duration - 1e-9:
            raise ExperimentFinished(f"declared duration {self.duration} s is over")
        v = np.asarray(v, dtype=float)
        w = np.asarray(w, dtype=float)
        self.last_nominal = self.last_safe = unicycle_to_si(self.robots.poses, v, w, self.ell)
        new_poses = self.robots.step(v, w)
        if self.sensors is not None:  # the robots' wheel limits scale what they run
            self._sense_after_step(new_poses, *limit_unicycle(v, w, self.params)[:2])
        self._annotate(self.time)
        if self._on_step is not None:
            self._on_step(self)
        return new_poses

    def read_annotations(self) -> None:
        """Say that something reads :attr:`last_annotations` (a recording does when it opens, the rps facade's
        ``arena`` property does when a script asks for its Arena): see :attr:`annotations_read`."""
        self._annotations_read = True

    @property
    def annotations_read(self) -> bool:
        """Whether anything may read what is drawn: :meth:`read_annotations` was called, the robots sit behind a
        trust boundary (their sink takes the annotations: the sandbox, the portal, the console's live view and
        projector), or a per-step hook runs (it gets the Arena; swarmdeck's progress bar says it does not read them:
        ``reads_annotations = False``). Work that only feeds the annotations may be skipped while this is False:
        the rps facade then does not project a script's matplotlib figure (:mod:`swarmdeck.devices.rps.figure`),
        which nothing would show; what an experiment draws itself (:attr:`draw`) is collected every step regardless."""
        if self._annotations_read or getattr(self.backend, "send_annotations", None) is not None:
            return True
        return self._on_step is not None and bool(getattr(self._on_step, "reads_annotations", True))

    def _annotate(self, time: float) -> None:
        """What :attr:`draw` holds for the step ending at ``time`` s → :attr:`last_annotations` (and, for robots
        behind a trust boundary, across it: their sink's ``send_annotations``); cap hits become events."""
        self.last_annotations = self.draw.collect(time)
        self.events.extend(f"t={time:.3f}: {m}" for m in self.draw.take_messages())
        send = getattr(self.backend, "send_annotations", None)
        if send is not None:
            send(self.last_annotations)

    # ------------------------------------------------------------------ reporting
    def report(self) -> ArenaReport:
        """What happened so far: validation counts, safety filter statistics, invalid commands."""
        validation = self.robots.report
        fleet = None if self.fleet is None else fleet_summary(self.fleet)
        return ArenaReport(self.n, self.time, validation, self.safety_stats, self.invalid_commands, self.safety is not None,
                           fleet)

    def call_at_scripts_end(self) -> None:
        """Print the report (rps compatibility) — unless a runner (``swarmdeck run``) runs the script:
        it prints the report once, at the end of the run."""
        if RUN_DEFAULTS.get().on_create is None:
            print(self.report())


def _simulated_robots(n_robots: int | None, initial_conditions: ArrayLike | None, *, config: ArenaConfig,
                      params: GritsBotParams) -> SimulatedRobots:
    """The Arena's robots when none are given: the simulator, pacing itself when ``config.real_time``."""
    return SimulatedRobots(sim=SimulatedArena(n_robots, initial_conditions, config=config, params=params))


@dataclass
class ArenaReport:
    """Summary of a run for people (``str``) and programs (``to_dict``)."""

    n_robots: int
    time: float
    validation: Any
    safety: SafetyStats
    invalid_commands: int
    safety_enabled: bool
    fleet: dict | None = None  # setup and return from the chargers (Arenas made from_docks)

    def to_dict(self) -> dict:
        out = {
            "n_robots": self.n_robots,
            "time": self.time,
            "validation": self.validation.to_dict() if self.validation is not None else None,
            "safety": {
                "enabled": self.safety_enabled,
                "calls": self.safety.calls,
                "failures": self.safety.failures,
                "failure_reasons": dict(self.safety.failure_reasons),
                "interventions": self.safety.interventions,
                "saturations": self.safety.saturations,
                "saturation_steps": self.safety.saturation_steps,
            },
            "invalid_commands": self.invalid_commands,
        }
        if self.fleet is not None:
            out["fleet"] = self.fleet
        return out

    def __str__(self) -> str:
        lines = ["swarmdeck run report"]
        if self.validation is not None:
            lines.append(self.validation.summary(invalid_upstream=self.invalid_commands,
                                                 saturated_upstream=(self.safety.saturations, self.safety.saturation_steps)))
        else:
            lines.append(f"robots: {self.n_robots}   time: {self.time:.2f} s")
            lines.append(f"invalid (NaN/inf) commands stopped: {self.invalid_commands} robot-steps")
        if self.safety_enabled:
            s = self.safety
            lines.append(
                f"safety filter: {s.calls} calls, {s.interventions} robot-steps changed, {s.failures} failures (robots stopped)"
                + (f" {s.failure_reasons}" if s.failure_reasons else "")
            )
        else:
            lines.append("safety filter: OFF")
        if self.fleet is not None:
            lines.append(describe_fleet(self.fleet))
        return "\n".join(lines)


def fleet_summary(fleet: Any) -> dict:
    """JSON-able account of a fleet's setup and return (``FleetManager.last_setup/last_return``)."""
    setup = fleet.last_setup.to_dict() if fleet.last_setup is not None else None
    ret = fleet.last_return.to_dict() if fleet.last_return is not None else None
    return {"setup": setup, "return": ret, "collisions": int(fleet.sim.report.steps_with_collision),
            "ready": bool(fleet.ready()), "robots": int(fleet.n_robots)}


def describe_fleet(summary: dict) -> str:
    """The fleet's lines of a run report: setup and return times, largest pose error, collisions."""
    s, r = summary["setup"], summary["return"]
    text = "fleet: "
    if s is not None:
        text += (f"set up from the chargers in {s['sim_time']:.1f} s simulated ({s['wall_time']:.1f} s wall), "
                 f"largest pose error {s['max_position_error'] * 100:.1f} cm / {s['max_heading_error_deg']:.1f} deg, "
                 f"{s['escapes']} deadlock escapes")
    text += ("; not returned" if r is None else
             f"; returned to the chargers in {r['sim_time']:.1f} s simulated ({r['wall_time']:.1f} s wall)"
             + ("" if r["ok"] else " (FAILED)"))
    return text + f"; collisions {summary['collisions']} steps; {'ready' if summary['ready'] else 'NOT ready'}"

