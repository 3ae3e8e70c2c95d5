"""``rps.robotarium.Robotarium`` on top of :class:`swarmdeck.devices.Arena`."""
from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.devices.arena import RUN_DEFAULTS, Arena
from swarmdeck.devices.simulator import ArenaConfig


class Robotarium:
    """The rps experiment object: ``get_poses()`` → (3, N), ``set_velocities(ids, (2, N))``, ``step()``.

    Args (as rps): number_of_robots (−1: the runner's ``--robots`` or 6),
    show_figure (ignored: use ``swarmdeck console`` to watch), sim_in_real_time
    (pace steps at 0.033 s of wall time), initial_conditions ((3, N) floats); swarmdeck's
    ``from_docks=True`` (or ``swarmdeck run --from-docks``) starts the robots on the chargers and
    sets them up to the initial conditions before the first step, as the Robotarium's back end does.
    """

    def __init__(self, number_of_robots: int = -1, show_figure: bool = True, sim_in_real_time: bool = True,
                 initial_conditions: ArrayLike = np.array([]), *, from_docks: bool | None = None) -> None:
        ic = np.asarray(initial_conditions)
        defaults = RUN_DEFAULTS.get()
        n = None if number_of_robots is None or number_of_robots < 0 else int(number_of_robots)
        if ic.size:
            if ic.ndim != 2 or ic.shape[0] != 3:
                raise ValueError(f"initial_conditions must have shape (3, N), got {ic.shape}")
            if n is not None and ic.shape[1] != n:
                raise ValueError(f"initial_conditions has {ic.shape[1]} columns but number_of_robots is {n}")
        real_time = bool(sim_in_real_time) and defaults.on_create is None  # never pace under `swarmdeck run`
        config = ArenaConfig(real_time=real_time, seed=defaults.seed)
        self._arena = Arena(n, initial_conditions=ic.T if ic.size else None, config=config, from_docks=from_docks)
        self.number_of_robots = self._arena.n
        self.show_figure = show_figure
        self.time_step = config.dt
        x0, x1, y0, y1 = config.bounds
        self.boundaries = [x0, y0, x1 - x0, y1 - y0]  # rps: [x_min, y_min, width, height]
        self._velocities = np.zeros((2, self.number_of_robots))
        self._checked_poses = False
        # the robot's constants under rps's names (REFERENCE.md §1)
        robot = self._arena.params
        self.robot_diameter = robot.diameter
        self.robot_radius = robot.radius
        self.wheel_radius = robot.wheel_radius
        self.base_length = robot.axle_length
        self.max_linear_velocity = robot.max_speed
        self.max_wheel_velocity = robot.max_wheel_speed
        self.max_angular_velocity = robot.max_angular_speed
        self._figure: Any = None

    @property
    def figure(self) -> Any:
        """rps's matplotlib figure, headless here (see :mod:`swarmdeck.devices.rps.figure`)."""
        if self._figure is None:
            from swarmdeck.devices.rps.figure import arena_figure

            self._figure = arena_figure(tuple(self.boundaries))
        return self._figure[0]

    @property
    def axes(self) -> Any:
        """rps's axes: plotting calls (``scatter``, ``text``, ``imshow``, …) work and are not shown."""
        self.figure  # noqa: B018 - creates it
        return self._figure[1]

    @property
    def arena(self) -> Arena:
        """The swarmdeck Arena underneath."""
        return self._arena

    def get_poses(self) -> NDArray[np.float64]:
        """Poses (3, N) [x; y; θ] — a copy (rps returns its internal array)."""
        self._checked_poses = True
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
        self._arena.set_unicycle(vel[0], vel[1], ids=idx)

    def step(self) -> None:
        """Advance one 0.033 s step (through swarmdeck's safety filter and wheel limits)."""
        self._arena.step()

    def call_at_scripts_end(self) -> None:
        """Print the run report, like rps's error summary."""
        print(self._arena.report())
