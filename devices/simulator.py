"""The simulated arena: GRITSBot physics on a virtual clock, validated every step.

This is the hardware stand-in. It knows nothing about controllers or safety:
it takes unicycle commands ``(v, ω)``, applies the wheel limits (one uniform
scale per robot, :func:`~swarmdeck.core.kinematics.limit_unicycle`), stops any
robot whose command is not finite, integrates the exact unicycle step and
counts boundary, collision and actuator errors the way rps does.

Line-segment obstacles (``ArenaConfig.obstacles``, :mod:`swarmdeck.core.obstacles`) are solid: a
robot whose step would cross a segment or bring its body (Ø ``GritsBotParams.diameter``) onto one
keeps its position (its heading still turns) — unless the step takes it farther from the segment,
so a robot already touching can back away. Contacts are counted in the validation report.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds, check_bounds
from swarmdeck.core.checks import require_in_range
from swarmdeck.core.constants import CONTROL_PERIOD
from swarmdeck.core.kinematics import GritsBotParams, limit_unicycle, unicycle_step, wrap_angle
from swarmdeck.core.obstacles import Obstacles, segments_cross, segments_near
from swarmdeck.devices.clock import RealTimePacer, VirtualClock
from swarmdeck.devices.initial_conditions import random_initial_poses
from swarmdeck.devices.validation import ValidationReport, ValidationRules


@dataclass(frozen=True)
class ArenaConfig:
    """The arena and its stepping (REFERENCE.md §1).

    Attributes:
        bounds: ``(x_min, x_max, y_min, y_max)`` of the floor, m.
        dt: control/integration period, s.
        real_time: sleep so that one step takes ``dt`` of wall time.
        seed: seed for random initial conditions (None: fresh entropy).
        obstacles: line-segment obstacles on the floor (:class:`~swarmdeck.core.obstacles.Obstacles`
            or anything ``Obstacles.of`` reads: ``(M, 2, 2)`` m, a config list), or None. Checked to lie
            inside ``bounds`` (ObstacleError naming the segment).
    """

    bounds: Bounds = DEFAULT_BOUNDS
    dt: float = CONTROL_PERIOD
    real_time: bool = False
    seed: int | None = None
    obstacles: Obstacles | None = None

    def __post_init__(self) -> None:
        check_bounds(self.bounds, "ArenaConfig.bounds")
        require_in_range(self.dt, "ArenaConfig.dt", 0.0, 1.0, unit="s", lo_open=True)
        if self.obstacles is not None:
            obs = Obstacles.of(self.obstacles).check_inside(self.bounds)
            object.__setattr__(self, "obstacles", obs or None)

    @property
    def segments(self) -> NDArray[np.float64]:
        """The obstacle segments ``(M, 2, 2)`` m (M = 0 without obstacles)."""
        return np.zeros((0, 2, 2)) if self.obstacles is None else self.obstacles.segments

    @property
    def width(self) -> float:
        return Bounds.of(self.bounds).width

    @property
    def height(self) -> float:
        return Bounds.of(self.bounds).height


def check_poses(poses: ArrayLike, name: str = "initial_conditions", n: int | None = None) -> NDArray[np.float64]:
    """Validate and copy a ``(N, 3)`` float pose array; a clear ValueError otherwise.

    Integer arrays are rejected (in rps they silently truncate the dynamics).
    """
    arr = np.asarray(poses)
    if arr.dtype.kind not in "f":
        raise ValueError(
            f"{name} must be a float array of shape (N, 3) [x, y, theta]; got dtype {arr.dtype} "
            "(integer poses would truncate the dynamics: use floats, e.g. np.array(..., dtype=float))"
        )
    if arr.ndim != 2 or arr.shape[1] != 3 or arr.shape[0] < 1:
        raise ValueError(f"{name} must have shape (N, 3) with N >= 1, got {arr.shape}")
    if n is not None and arr.shape[0] != n:
        raise ValueError(f"{name} has {arr.shape[0]} rows but the arena has {n} robots")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} contains NaN or inf")
    out = arr.astype(float, copy=True)
    out[:, 2] = wrap_angle(out[:, 2])
    return out


@dataclass
class SimulatedArena:
    """N simulated GRITSBots on the arena floor.

    Args:
        n_robots: N; ignored when ``initial_poses`` is given.
        initial_poses: ``(N, 3)`` float array, or None for random non-overlapping poses.
        config: the arena.
        params: the robot model.
        rules: validation thresholds.
    """

    n_robots: int | None = None
    initial_poses: ArrayLike | None = None
    config: ArenaConfig = field(default_factory=ArenaConfig)
    params: GritsBotParams = field(default_factory=GritsBotParams)
    rules: ValidationRules = field(default_factory=ValidationRules)

    def __post_init__(self) -> None:
        segments = self.config.segments
        if self.initial_poses is not None and np.asarray(self.initial_poses).size:
            self._poses = check_poses(self.initial_poses)
            if self.config.obstacles is not None:
                # the physics refuses a body on a segment; the Arena asks for START_CLEARANCE
                self.config.obstacles.check_clear(self._poses, self.params.diameter / 2, "start pose")
            if self.n_robots is not None and self.n_robots != self._poses.shape[0]:
                raise ValueError(
                    f"n_robots={self.n_robots} disagrees with initial_poses of {self._poses.shape[0]} rows"
                )
        else:
            if self.n_robots is None:
                raise ValueError("give n_robots or initial_poses")
            self._poses = random_initial_poses(self.n_robots, self.config.bounds, rng=self.config.seed,
                                               obstacles=segments)
        self.n_robots = self._poses.shape[0]
        self.clock = VirtualClock()
        self.report = ValidationReport(self.n_robots)
        self._pacer = RealTimePacer(self.config.dt) if self.config.real_time else None
        self._v = np.zeros(self.n_robots)
        self._w = np.zeros(self.n_robots)
        self.last_collisions = np.empty((0, 2), dtype=np.intp)

    @property
    def n(self) -> int:
        """Number of robots N (what ``n_robots`` holds once the arena is built)."""
        return int(self._poses.shape[0])

    @property
    def poses(self) -> NDArray[np.float64]:
        """Current poses ``(N, 3)``; a copy, so callers can never alter the simulation."""
        return self._poses.copy()

    @property
    def time(self) -> float:
        """Simulated time, s."""
        return self.clock.now

    @property
    def applied(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The ``(v, ω)`` actually applied in the last step, after limits (copies)."""
        return self._v.copy(), self._w.copy()

    def step(self, v: ArrayLike, w: ArrayLike) -> NDArray[np.float64]:
        """Apply ``(v, ω)`` (each ``(N,)``) for one period; returns the new poses (a copy).

        Non-finite commands stop that robot (and are counted); wheel limits scale
        v and ω together; errors are counted in :attr:`report`.
        """
        v = np.asarray(v, dtype=float).reshape(-1)
        w = np.asarray(w, dtype=float).reshape(-1)
        n = self.n_robots
        if v.shape != (n,) or w.shape != (n,):
            raise ValueError(f"v and w must each have shape ({n},), got {v.shape} and {w.shape}")
        invalid = ~(np.isfinite(v) & np.isfinite(w))
        if invalid.any():
            v = np.where(invalid, 0.0, v)
            w = np.where(invalid, 0.0, w)
        v, w, saturated = limit_unicycle(v, w, self.params)
        self._v, self._w = v, w
        new = unicycle_step(self._poses, v, w, self.config.dt)
        if self.config.obstacles is not None:
            new = self._blocked(self._poses, new)
        self._poses = new
        t = self.clock.advance(self.config.dt)
        self.last_collisions = self.report.record(self._poses, self.config.bounds, saturated, invalid, t, self.rules,
                                                  obstacles=self.config.obstacles)
        if self._pacer is not None:
            self._pacer.wait()
        return self._poses.copy()

    def _blocked(self, old: NDArray[np.float64], new: NDArray[np.float64]) -> NDArray[np.float64]:
        """``new`` with the robots a segment stops kept at their ``old`` position (their heading still turns).

        A robot is stopped when its move crosses a segment, or ends with its body on one (centre closer
        than the body radius) nearer than it started. Candidates only (k-d tree), no N × M array."""
        seg = self.config.segments
        body = self.params.diameter / 2
        step = float(np.max(np.hypot(*(new[:, :2] - old[:, :2]).T), initial=0.0))
        i, k, _ = segments_near(old[:, :2], seg, body + step)
        if i.size == 0:
            return new
        robots = np.unique(i)
        crossed = segments_cross(old[robots, :2], new[robots, :2], seg)
        d_new = np.full(robots.size, np.inf)
        d_old = np.full(robots.size, np.inf)
        ni, _, nd = segments_near(new[robots, :2], seg, body)
        np.minimum.at(d_new, ni, nd)
        oi, _, od = segments_near(old[robots, :2], seg, body)
        np.minimum.at(d_old, oi, od)
        stop = robots[crossed | ((d_new < body) & (d_new < d_old))]
        if stop.size == 0:
            return new
        out = new.copy()
        out[stop, :2] = old[stop, :2]
        return out
