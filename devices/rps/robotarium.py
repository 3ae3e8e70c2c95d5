"""``rps.robotarium.Robotarium`` on top of :class:`swarmdeck.devices.Arena`.

Two modes (REFERENCE.md §2, §15):

* default — the script runs as the arena would run it: every ``step()`` goes through swarmdeck's
  safety filter and wheel limits;
* rps semantics (``Robotarium(…, rps_semantics=True)``, ``swarmdeck run --rps-semantics``) — as rps: the
  barrier applies only where the script calls one, and nothing else filters its commands (the wheel
  limits still scale them, as :func:`~swarmdeck.core.kinematics.limit_unicycle` does, not rps's
  per-wheel clipping).

In both, rps's error counts are kept in ``_errors`` and printed by ``debug()`` (rps 2.0) and — in rps
semantics — ``call_at_scripts_end()`` (rps 1.x), see :mod:`swarmdeck.devices.rps.errors`; and rps's call
order is enforced: ``get_poses()`` once per ``step()``, no ``step()`` without ``get_poses()`` before it,
with rps's ``AssertionError`` (``enforce_call_order=False`` or ``swarmdeck run --no-rps-call-order``
relaxes it).
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.bounds import Bounds
from swarmdeck.core.constants import RPS_MAX_ROBOTS
from swarmdeck.core.kinematics import limit_unicycle
from swarmdeck.core.obstacles import Obstacles
from swarmdeck.core.robot_models import DEFAULT_ROBOT_MODEL, model_name, robot_params
from swarmdeck.devices.arena import RUN_DEFAULTS, Arena
from swarmdeck.devices.rps import quiet_canvas
from swarmdeck.devices.rps.errors import call_at_scripts_end_text, count_errors, debug_text
from swarmdeck.devices.rps.figure_annotations import Colours, figure_annotations
from swarmdeck.devices.rps.robotarium_abc import ARobotarium
from swarmdeck.devices.rps.sensors import RpsSensors, sensing_for
from swarmdeck.devices.simulated_robots import SimulatedRobots

RELAX_HINT = ("swarmdeck enforces rps's call order as the Robotarium does; Robotarium(..., enforce_call_order=False) "
              "or `swarmdeck run --no-rps-call-order` relaxes it")
# rps's own messages (1.x `dev` branch / 2.0 `master`: the same rule, worded slightly differently)
GET_POSES_TWICE = "Can only call get_poses() once per call of step()!"
STEP_TWICE = "Make sure you call get_poses before calling step()!"
#: rps 2.x's drawing flags (``show_*``): accepted, nothing is drawn (watch in ``swarmdeck console`` or a recording)
SHOW_FLAGS_2X = ("show_arena_boundaries", "show_robot_patches", "show_distance_endpoints", "show_distance_rays",
                 "show_obstacles")
#: every keyword the facade's constructor takes: rps 1.x and 2.x (robotarium.py, robotarium_abc.py) and swarmdeck's
KNOWN_ARGUMENTS = ("number_of_robots", "show_figure", "sim_in_real_time", "initial_conditions", "use_distance_sensors",
                   "obstacles", "skip_initialization", *SHOW_FLAGS_2X, "from_docks", "rps_semantics",
                   "enforce_call_order", "robot_model")
#: arguments of other Robotarium front ends that swarmdeck does not take, and what to use instead
INSTEAD = {
    "robot_type": "robot_model='gritsbot' or 'gternal' (or `swarmdeck run --robot-model`)",
    "boundaries": "the arena's bounds: `swarmdeck console --config` ([console] bounds/arena)",
    "time_step": "the control period is fixed at 0.033 s (REFERENCE.md §1)",
    "seed": "`swarmdeck run --seed N`",
    "show_robot_ids": "`swarmdeck console` or `swarmdeck play` (labels)",
}


def check_obstacles(obstacles: Any) -> NDArray[np.float64]:
    """rps 2.x's ``obstacles``: an (M, 2, 2) float array of segment endpoints ``[[x0, y0], [x1, y1]]``, m — a copy;
    a ValueError naming the argument, the shape and the first bad segment otherwise."""
    try:
        arr = np.array(obstacles, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"obstacles must have shape (M, 2, 2) (segment endpoints [[x0, y0], [x1, y1]] in m), got "
                         f"{obstacles!r:.80}") from None
    if arr.size == 0:
        return np.zeros((0, 2, 2))
    if arr.ndim != 3 or arr.shape[1:] != (2, 2):
        raise ValueError(f"obstacles must have shape (M, 2, 2) (segment endpoints [[x0, y0], [x1, y1]] in m), "
                         f"got shape {arr.shape}")
    bad = np.flatnonzero(~np.isfinite(arr).all(axis=(1, 2)))
    if bad.size:
        raise ValueError(f"obstacles[{bad[0]}] has a NaN or infinite coordinate: {arr[bad[0]].tolist()}")
    return arr


def unsupported_argument_message(names: list[str]) -> str:
    """The error for constructor keywords the facade does not take: each named, with what to use instead."""
    import difflib

    parts = []
    for name in names:
        hint = INSTEAD.get(name)
        if hint is None:
            close = difflib.get_close_matches(name, KNOWN_ARGUMENTS, n=1)
            hint = f"did you mean {close[0]!r}?" if close else f"it takes {', '.join(KNOWN_ARGUMENTS)}"
        parts.append(f"{name!r} (use {hint})" if name in INSTEAD else f"{name!r} ({hint})")
    return ("Robotarium() got argument(s) swarmdeck's rps facade does not support: " + "; ".join(parts))


def _with_lab_obstacles(script: NDArray[np.float64] | None, lab: Any) -> Obstacles | None:
    """The script's checked ``obstacles`` (M, 2, 2) and the lab's (``RunDefaults.obstacles``) as one
    :class:`~swarmdeck.core.obstacles.Obstacles` (ObstacleError naming a zero-length segment); None without any."""
    parts = [o.segments for o in (Obstacles.of(lab), Obstacles.of(script)) if o]
    return Obstacles(np.concatenate(parts)) if parts else None


class Robotarium(RpsSensors, ARobotarium):
    """The rps experiment object: ``get_poses()`` → (3, N), ``set_velocities(ids, (2, N))``, ``step()``.

    Args (as rps, positional as in 1.x or keywords as in 2.x — every name of 2.x's ``robotarium.py`` and
    ``robotarium_abc.py``): number_of_robots (−1: the runner's ``--robots`` or 6; at most 50 as in rps),
    show_figure (ignored: use ``swarmdeck console`` to watch), sim_in_real_time (pace steps at 0.033 s of wall
    time; never under ``swarmdeck run``), initial_conditions ((3, N) floats). rps 2.x's ``skip_initialization``
    and ``show_*`` flags are accepted (the robots start at their initial conditions — ``swarmdeck run
    --from-docks`` drives them there from the chargers, as 2.x's initialisation phase does; nothing is drawn);
    ``obstacles`` (M × 2 × 2, checked) are solid, beside the lab's ``[arena] obstacles``: the sensors see them (as
    in rps 2.0), and swarmdeck's barrier, the simulator's contact and validation hold them too (``self.obstacles``:
    all of them). rps 2.0's sensors
    (:mod:`swarmdeck.devices.rps.sensors`): ``use_distance_sensors=True`` simulates the seven ToF sensors; encoders,
    IMU and LEDs are always there. Flags must be bools (rps 2.x's own checks); any other keyword is refused, named,
    with what to use instead.
    swarmdeck's keywords: ``from_docks=True`` (``swarmdeck run --from-docks``) starts the robots on the
    chargers and sets them up first; ``rps_semantics`` and ``enforce_call_order`` (None: the runner's,
    else False and True) choose the modes of the module docstring; ``robot_model`` (``"gritsbot"`` or
    ``"gternal"``; None: ``swarmdeck run --robot-model``, else the GTernal for a 2.x script and the GRITSBot
    for a 1.x one, :mod:`swarmdeck.devices.rps.generation`) the robots' drive and body, and with them the
    constants (``BASE_LENGTH``, ``MAX_ANGULAR_VELOCITY``, …) the instance reports.
    """

    def __init__(self, number_of_robots: int = -1, show_figure: bool = True, sim_in_real_time: bool = True,
                 initial_conditions: ArrayLike = np.array([]), *, from_docks: bool | None = None,
                 rps_semantics: bool | None = None, enforce_call_order: bool | None = None,
                 use_distance_sensors: bool = False, obstacles: Any = None, skip_initialization: bool = False,
                 robot_model: str | None = None, **kwargs: Any) -> None:
        unknown = sorted(set(kwargs) - set(SHOW_FLAGS_2X))
        if unknown:
            raise TypeError(unsupported_argument_message(unknown))
        for flag, value in (("show_figure", show_figure), ("sim_in_real_time", sim_in_real_time),
                            ("use_distance_sensors", use_distance_sensors),
                            ("skip_initialization", skip_initialization), *kwargs.items()):
            if not isinstance(value, (bool, np.bool_)):  # as rps 2.x's strict checks (rps/robotarium.py)
                raise TypeError(f"Robotarium(): {flag} must be True or False (rps 2.x checks it too), got {value!r}")
        self.show_flags = {name: bool(kwargs.get(name, name != "show_distance_rays")) for name in SHOW_FLAGS_2X}
        sensing = sensing_for(use_distance_sensors)
        quiet_canvas()  # a script that imported pyplot first: its figures' redraws cost nothing either
        obstacles = None if obstacles is None else check_obstacles(obstacles)
        ic = np.asarray(initial_conditions)
        defaults = RUN_DEFAULTS.get()
        n = None if number_of_robots is None or number_of_robots < 0 else int(number_of_robots)
        if n is not None and n > RPS_MAX_ROBOTS:
            raise ValueError(f"number_of_robots={n}: rps simulates at most {RPS_MAX_ROBOTS} robots (the Robotarium "
                             "runs at most 20); for larger swarms use swarmdeck's Arena or `swarmdeck console`")
        if ic.size:
            if ic.ndim != 2 or ic.shape[0] != 3:
                raise ValueError(f"initial_conditions must have shape (3, N) [x; y; theta], got {ic.shape}")
            if n is not None and ic.shape[1] != n:
                raise ValueError(f"initial_conditions has {ic.shape[1]} columns but number_of_robots is {n}")
            if ic.dtype.kind != "f":  # speak rps's (3, N) here, not the Arena's (N, 3)
                raise ValueError(
                    f"initial_conditions must be a float array of shape (3, N) [x; y; theta]; got dtype {ic.dtype} "
                    "(integer poses would truncate the dynamics in rps: use floats, e.g. np.array(..., dtype=float))")
        self.rps_semantics = defaults.rps_semantics if rps_semantics is None else bool(rps_semantics)
        self.enforce_call_order = defaults.rps_call_order if enforce_call_order is None else bool(enforce_call_order)
        real_time = bool(sim_in_real_time) and defaults.on_create is None  # never pace under `swarmdeck run`
        config = defaults.arena_config(real_time=real_time)
        if robot_model is None:
            robot_model = defaults.robot_model or ("gternal" if defaults.rps_generation == 2 else DEFAULT_ROBOT_MODEL)
        # the script's obstacles are solid (barrier, contact, validation, sensors) beside the lab's ([arena] obstacles,
        # swarmdeck run --obstacles); under a sandbox the trusted side receives them with the Arena and adds them
        solid = _with_lab_obstacles(obstacles, defaults.obstacles)
        self._arena = Arena(n, initial_conditions=ic.T if ic.size else None, config=config, from_docks=from_docks,
                            safety=False if self.rps_semantics else None, params=robot_params(robot_model),
                            obstacles=solid)
        self.robot_model = model_name(self._arena.params) or robot_model
        self.number_of_robots = self._arena.n
        self._arena.use_sensors(sensing)  # the Arena's segments: the script's and the lab's
        # rps 2.x: what is on the floor, (M, 2, 2) (an empty array stays one); None when neither gave any
        self.obstacles = np.array(solid.segments) if solid is not None else obstacles
        self.show_figure = show_figure
        self.time_step = config.dt
        b = Bounds.of(config.bounds)
        x0, x1, y0, y1 = self._bounds = b
        self.boundaries = [x0, y0, b.width, b.height]  # rps 1.x: [x_min, y_min, width, height]
        self.BOUNDARIES = np.array([x0, x1, y0, y1])  # rps 2.0: [x_min, x_max, y_min, y_max]
        self._velocities = np.zeros((2, self.number_of_robots))
        # rps's call-order state: as after rps's own set-up, the script's first call must be get_poses()
        self._called_step_already = True
        self._checked_poses_already = False
        self._errors: dict[str, Any] = {}
        self._iterations = 0
        # the robot's constants under rps's names (REFERENCE.md §1)
        robot = self._arena.params
        self.robot_diameter = self.ROBOT_DIAMETER = robot.diameter
        self.robot_radius = robot.radius
        self.wheel_radius = self.WHEEL_RADIUS = robot.wheel_radius
        self.base_length = self.BASE_LENGTH = robot.axle_length
        self.max_linear_velocity = self.MAX_LINEAR_VELOCITY = robot.max_speed
        self.max_wheel_velocity = self.MAX_WHEEL_VELOCITY = robot.max_wheel_speed
        self.max_angular_velocity = self.MAX_ANGULAR_VELOCITY = robot.max_angular_speed
        self.collision_offset = self.COLLISION_OFFSET
        self.collision_diameter = self.COLLISION_DIAMETER
        self.robot_length, self.robot_width = 0.095, 0.09  # rps 1.x's drawing sizes
        self.initial_conditions = ic.astype(float) if ic.size else self._arena.poses().T
        self.initializing = False
        self.skip_initialization = bool(skip_initialization)
        self._sim_in_real_time = real_time
        self._figure: Any = None
        self._colours = Colours()  # the figure's colour conversions, by value, from step to step

    # ------------------------------------------------------------------ figure
    @property
    def figure(self) -> Any:
        """rps's matplotlib figure, headless here (see :mod:`swarmdeck.devices.rps.figure`)."""
        if self._figure is None:
            from swarmdeck.devices.rps.figure import arena_figure

            x0, y0, w, h = self.boundaries
            self._figure = arena_figure((x0, y0, w, h))
        return self._figure[0]

    @property
    def axes(self) -> Any:
        """rps's axes: plotting calls (``scatter``, ``text``, ``imshow``, …) work and are not shown."""
        self.figure  # noqa: B018 - creates it
        return self._figure[1]

    _axes_handle = axes  # rps 2.0's name

    @property
    def _fig(self) -> Any:
        """rps 2.0's name of the figure (headless: ``canvas.draw_idle()``, ``mpl_connect`` work, nothing shows)."""
        return self.figure

    @property
    def arena(self) -> Arena:
        """The swarmdeck Arena underneath (asking for it counts as reading its annotations: from then on the
        figure is projected every step, :meth:`Arena.read_annotations`)."""
        self._arena.read_annotations()
        return self._arena

    # ------------------------------------------------------------------ rps's API
    def initialize(self, initial_conditions: ArrayLike) -> None:
        """rps 2.x's initialisation phase, which drives the robots to ``initial_conditions`` before the experiment.
        Here the robots are at their initial conditions when the constructor returns (``swarmdeck run --from-docks``
        drives them there from the chargers), so a second call is refused with what to do instead."""
        raise RuntimeError("Robotarium.initialize(): the robots are at their initial conditions already (give them as "
                           "Robotarium(initial_conditions=...); `swarmdeck run --from-docks` drives them there from "
                           "the chargers as the Robotarium's initialisation phase does)")

    @property
    def poses(self) -> NDArray[np.float64]:
        """rps 1.x's ``poses`` attribute: (3, N), a copy (reading it is not a ``get_poses()`` call)."""
        return self._arena.poses().T.copy()

    @property
    def velocities(self) -> NDArray[np.float64]:
        """rps 1.x's ``velocities``: the (2, N) [v; ω] last set, a copy."""
        return self._velocities.copy()

    def get_poses(self) -> NDArray[np.float64]:
        """Poses (3, N) [x; y; θ] — a copy (rps returns its internal array). Once per ``step()``."""
        if self.enforce_call_order and self._checked_poses_already:
            raise AssertionError(f"{GET_POSES_TWICE} ({RELAX_HINT})")
        self._called_step_already = False
        self._checked_poses_already = True
        return self._arena.poses().T.copy()

    def set_velocities(self, ids: ArrayLike, velocities: ArrayLike) -> None:
        """Unicycle commands (2, len(ids)) [v; ω] for robots ``ids``."""
        vel = np.asarray(velocities, dtype=float)
        idx = np.atleast_1d(np.asarray(ids))
        if vel.ndim != 2 or vel.shape[0] != 2:
            raise ValueError(f"velocities must have shape (2, N), got {vel.shape}")
        if idx.dtype == bool:
            if idx.shape != (self.number_of_robots,):
                raise ValueError(f"a boolean ids mask must have shape ({self.number_of_robots},), got {idx.shape}")
            idx = np.flatnonzero(idx)
        elif idx.dtype.kind == "f" and np.all(np.isfinite(idx)) and np.all(idx == np.round(idx)):
            idx = idx.astype(int)  # rps scripts pass np.arange(N) as floats sometimes; whole numbers only
        elif idx.dtype.kind not in "iu":
            raise ValueError(f"ids must be robot indices (integers), got {idx.tolist()!r}")
        if vel.shape[1] != len(idx):
            raise ValueError(f"velocities has {vel.shape[1]} columns for {len(idx)} ids")
        if not self.rps_semantics:  # (rps semantics: step() hands the velocities to the robots itself)
            n = self.number_of_robots  # every robot in order (rps scripts pass np.arange(N)): the same command
            every = idx.shape == (n,) and bool((idx == np.arange(n)).all())
            self._arena.set_unicycle(vel[0], vel[1], ids=None if every else idx)
        self._velocities[:, idx] = vel

    def step(self) -> None:
        """Validate as rps does (into ``_errors``), then advance one 0.033 s step: through swarmdeck's
        safety filter and wheel limits (default), or the wheel limits only (rps semantics)."""
        if self.enforce_call_order and self._called_step_already:
            raise AssertionError(f"{STEP_TWICE} ({RELAX_HINT})")
        self._called_step_already = True
        self._checked_poses_already = False
        self._errors = self._validate(self._errors)
        self._iterations += 1
        self._project_figure()
        if self.rps_semantics:  # as rps: the velocities go to the robots as they are (wheel limits apply)
            self._arena.step_unicycle(self._velocities[0], self._velocities[1])
        else:
            self._arena.step()

    def _project_figure(self) -> None:
        """What the script plotted on :attr:`axes` inside the arena → the arena's annotations for this step
        (the Robotarium 2.0 projects it onto the testbed); nothing when the script never touched the figure, or
        when nothing reads the arena's annotations (:attr:`Arena.annotations_read`: a headless ``swarmdeck run``
        without ``--record`` shows no figure, so it is not projected)."""
        if self._figure is None or not self._arena.annotations_read:
            return
        x0, x1, y0, y1 = self._bounds
        self._arena.draw.add(figure_annotations(self._figure[1], (x0, x1, y0, y1), colours=self._colours), key="rps-figure")

    def _validate(self, errors: dict | None = None) -> dict:
        """rps's validation of the current poses and commanded velocities, counted into ``errors``
        (a new dict when None: never a shared default, unlike rps 1.x); returns it."""
        errors = {} if errors is None else errors
        robots = self._arena.backend
        pairs = None
        if isinstance(robots, SimulatedRobots) and robots.sim.report.steps:
            pairs = robots.sim.last_collisions  # the simulator validated these very poses after its last step
        v, w = self._velocities
        limit = 2 * self.wheel_radius * self.max_wheel_velocity  # |2v ± Lω| / (2r) > max wheel speed
        two_v, turn = 2 * v, self.base_length * w
        over = bool((np.abs(two_v - turn) > limit).any() or (np.abs(two_v + turn) > limit).any())
        count_errors(errors, self._arena.poses(), over, self._bounds, pairs)
        return errors

    def _threshold(self, dxu: ArrayLike) -> NDArray[np.float64]:
        """(2, N) [v; ω] within the wheel limits — swarmdeck's uniform scale per robot (what the robots
        get), not rps's per-wheel clipping, which changes the direction of motion."""
        dxu = np.asarray(dxu, dtype=float)
        v, w, _ = limit_unicycle(dxu[0], dxu[1], self._arena.params)
        return np.vstack((v, w))

    def _uni_to_diff(self, dxu: ArrayLike) -> NDArray[np.float64]:
        """rps's (2, N) wheel speeds, rad/s, from [v; ω]: rows (2v − Lω)/(2r), (2v + Lω)/(2r)."""
        dxu = np.asarray(dxu, dtype=float)
        r, base = self.wheel_radius, self.base_length
        return np.vstack(((2 * dxu[0] - base * dxu[1]) / (2 * r), (2 * dxu[0] + base * dxu[1]) / (2 * r)))

    def _diff_to_uni(self, dxdd: ArrayLike) -> NDArray[np.float64]:
        """rps's [v; ω] (2, N) from the wheel speeds of :meth:`_uni_to_diff`."""
        dxdd = np.asarray(dxdd, dtype=float)
        r, base = self.wheel_radius, self.base_length
        return np.vstack((r / 2 * (dxdd[0] + dxdd[1]), r / base * (dxdd[1] - dxdd[0])))

    def robot_colormap(self) -> Any:
        """rps 2.0: the matplotlib colormap robots are drawn with (``tab20``)."""
        import matplotlib

        return matplotlib.colormaps["tab20"]

    @property
    def _iteration(self) -> int:
        """rps 2.0's name for the step count."""
        return self._iterations

    def debug(self) -> None:
        """Print rps 2.0's end-of-run summary of ``_errors``."""
        print(debug_text(self._errors, self._iterations, self.time_step))

    def call_at_scripts_end(self) -> None:
        """rps 1.x's end-of-script call. Under rps semantics it prints rps's error summary; otherwise
        the swarmdeck run report — once: under ``swarmdeck run`` the runner prints it at the end."""
        if self.rps_semantics:
            print(call_at_scripts_end_text(self._errors, self._iterations, self.time_step))
        elif RUN_DEFAULTS.get().on_create is None:
            print(self._arena.report())
