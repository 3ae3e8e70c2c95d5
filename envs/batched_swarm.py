"""E swarms of N GRITSBots stepped at once: arrays of shape (E, N, …), the arena's pipeline bit for bit.

One tick of :meth:`BatchedSwarm.tick` is what :meth:`swarmdeck.devices.Arena.step` does for each
swarm, on all E·N robots at once: :func:`swarmdeck.devices.pipeline.certify` (non-finite rows stop,
the look-ahead map, the wheel limits by one scale per robot), the distributed barrier for every
swarm (:class:`~swarmdeck.envs.batched_barrier.BatchedDistributedBarrier`; a swarm whose barrier
fails stops, the others carry on), the simulator's wheel limits and the exact unicycle step
(:func:`swarmdeck.core.kinematics.unicycle_step`). So swarm e equals an ``Arena`` with the
distributed barrier (``swarmdeck.envs.parallel_env(..., barrier="distributed")``) fed the same
commands, bit for bit. No per-robot Python loop; neighbour queries by one compiled sweep (:mod:`swarmdeck.envs.neighbours`).

Units: poses (E, N, 3) ``[x, y, θ]`` m/rad; look-ahead velocities (E, N, 2) m/s; ``dt`` s.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.constants import CONTROL_PERIOD
from swarmdeck.core.kinematics import GritsBotParams, limit_unicycle, unicycle_step, unicycle_to_si, wrap_angle
from swarmdeck.devices.pipeline import certify
from swarmdeck.devices.validation import ValidationRules
from swarmdeck.envs import batched_kernels as kern
from swarmdeck.envs.batched_barrier import BatchedDistributedBarrier
from swarmdeck.envs.neighbours import swarm_pairs

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@dataclass(frozen=True)
class TickResult:
    """What one tick did, per robot ``(E, N)`` or per swarm ``(E,)``.

    filter_change: ‖u*_i − û_i‖ the barrier changed the look-ahead velocity, m/s (0 with the barrier off);
    command_change: how much the whole pipeline (wheel limits and barrier) changed it, m/s;
    filter_ok: (E,) the swarm's barrier certified its answer (False: its robots were stopped);
    collision: (E,) two robots collide by the rps test after the tick; boundary: (E,) a centre left the floor.
    """

    filter_change: FloatArray
    command_change: FloatArray
    filter_ok: BoolArray
    collision: BoolArray
    boundary: BoolArray


class BatchedSwarm:
    """E swarms of N robots (module docstring). ``safety``: the distributed barrier on (True) or off."""

    def __init__(self, n_swarms: int, n_robots: int, *, bounds: Bounds = DEFAULT_BOUNDS, dt: float = CONTROL_PERIOD,
                 safety: bool = True, params: GritsBotParams | None = None,
                 rules: ValidationRules = ValidationRules()) -> None:
        from swarmdeck.safety import BarrierConfig

        for name, value in (("n_swarms", n_swarms), ("n_robots", n_robots)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
                raise ValueError(f"{name} must be an int >= 1, got {value!r}")
        self.n_swarms, self.n_robots = int(n_swarms), int(n_robots)
        self.bounds, self.dt, self.rules = bounds, float(dt), rules
        self.params = GritsBotParams() if params is None else params
        self.barrier = BatchedDistributedBarrier(BarrierConfig(bounds=bounds, dt=dt), self.params) if safety else None
        self._cache: tuple[FloatArray, FloatArray, FloatArray, FloatArray | None] | None = None
        self.poses = np.zeros((self.n_swarms, self.n_robots, 3))

    @property
    def poses(self) -> FloatArray:
        """(E, N, 3) every robot's pose ``[x, y, θ]``, m/rad (read-only: place robots with :meth:`set_poses`)."""
        return self._poses

    @poses.setter
    def poses(self, value: FloatArray) -> None:
        new = np.array(value, dtype=float).reshape(self.n_swarms, self.n_robots, 3)
        new.setflags(write=False)
        self._poses = new
        self._cache = None

    def _trig(self) -> tuple[FloatArray, FloatArray]:
        """(cos θ, sin θ) (E·N,) of the current poses, computed once per pose update (on the same strided view
        as ``core.kinematics``, so the bits are the same)."""
        if self._cache is None:
            theta = self._poses.reshape(-1, 3)[:, 2]
            self._cache = (self._poses, np.cos(theta), np.sin(theta), None)
        return self._cache[1], self._cache[2]

    def points(self) -> FloatArray:
        """(E, N, 2) look-ahead points, m (a new array each call)."""
        return self._points_flat().reshape(self.n_swarms, self.n_robots, 2).copy()

    def _points_flat(self) -> FloatArray:
        """(E·N, 2) look-ahead points, m: the cached read-only array."""
        c, s = self._trig()
        assert self._cache is not None
        pts = self._cache[3]
        if pts is None:  # lookahead_points with the cached cos θ, sin θ: x + ℓ cos θ, y + ℓ sin θ
            flat = self._poses.reshape(-1, 3)
            ell = self.params.lookahead
            pts = np.column_stack((flat[:, 0] + ell * c, flat[:, 1] + ell * s))
            pts.setflags(write=False)
            self._cache = (self._cache[0], c, s, pts)
        return pts

    def set_poses(self, poses: FloatArray, swarms: NDArray[np.intp] | None = None) -> None:
        """Place the robots: poses (E, N, 3), or (len(swarms), N, 3) for the given swarms only."""
        new = self.poses.copy()
        if swarms is None:
            new[:] = poses
        else:
            new[swarms] = poses
        self.poses = new

    def tick(self, nominal: FloatArray, check: bool = True) -> TickResult:
        """Advance every swarm one period ``dt`` under look-ahead velocities ``(E, N, 2)`` m/s (rows with NaN or
        inf stop that robot). ``check``: test for collisions and boundary violations after the tick (else both
        all False)."""
        e, n = self.n_swarms, self.n_robots
        nom = np.asarray(nominal, dtype=float).reshape(e * n, 2)
        if not kern.use_compiled(e * n):
            return self._tick_numpy(nom, check)
        flat = self._poses.reshape(e * n, 3)
        c, s = self._trig()
        p = self.params
        m = e * n
        v, w = np.empty(m), np.empty(m)
        invalid = np.empty(m, dtype=bool)
        last_nominal = np.empty((m, 2))
        kern.certify_off(c, s, np.ascontiguousarray(nom), p.lookahead, p.axle_length, 2.0 * p.wheel_radius,
                         p.max_wheel_speed, p.max_wheel_speed * (1.0 + 1e-12), v, w, invalid, last_nominal)
        if self.barrier is None:
            ok = np.ones(e, dtype=bool)
            change = np.zeros(m)
        else:
            res = self.barrier.filter(flat, v, w, e, trig=(c, s), points=self._points_flat())
            v, w, ok, change = res.v, res.w, res.ok, res.intervention
        # the simulator's own wheel limits (limit_unicycle) are a no-op after the pipeline's: skipped
        command_change, a, small, a_safe = np.empty(m), np.empty(m), np.empty(m, dtype=bool), np.empty(m)
        kern.step_prepare(c, s, v, w, last_nominal, p.lookahead, self.dt, command_change, a, small, a_safe)
        cube = a**3 if small.any() else a  # read only where small (unicycle_step's series)
        new = np.empty((m, 3))
        heading = np.empty(m)
        kern.step_move(flat, c, s, v, a, small, a_safe, np.sin(a_safe), np.cos(a_safe), cube, self.dt, new, heading)
        new[:, 2] = wrap_angle(heading)
        self.poses = new.reshape(e, n, 3)
        return self._result(change, command_change, ok, check)

    def _tick_numpy(self, nom: FloatArray, check: bool) -> TickResult:
        """:meth:`tick` in numpy (without numba): the arena's functions themselves."""
        e, n = self.n_swarms, self.n_robots
        flat = self._poses.reshape(e * n, 3)
        cert = certify(flat, nom, self.params, None)
        if self.barrier is None:
            v, w = cert.v, cert.w
            ok = np.ones(e, dtype=bool)
            change = np.zeros(e * n)
        else:
            res = self.barrier.filter(flat, cert.v, cert.w, e)
            v, w, ok, change = res.v, res.w, res.ok, res.intervention
        safe = unicycle_to_si(flat, v, w, self.params.lookahead)
        last_nominal = np.where(cert.invalid[:, None], 0.0, nom)
        command_change = np.linalg.norm(safe - last_nominal, axis=1)
        v, w, _ = limit_unicycle(v, w, self.params)  # the simulated robots' own limits (a no-op after the pipeline)
        self.poses = unicycle_step(flat, v, w, self.dt).reshape(e, n, 3)
        return self._result(change, command_change, ok, check)

    def _result(self, change: FloatArray, command_change: FloatArray, ok: BoolArray, check: bool) -> TickResult:
        e, n = self.n_swarms, self.n_robots
        if check:
            collision, boundary = self.violations()
        else:
            collision = boundary = np.zeros(e, dtype=bool)
        return TickResult(change.reshape(e, n), command_change.reshape(e, n), ok, collision, boundary)

    def violations(self) -> tuple[BoolArray, BoolArray]:
        """(E,) swarms with a collision (rps test: centres shifted ``collision_shift`` forward closer than
        ``collision_distance``) and (E,) swarms with a centre outside the floor."""
        p = self.poses
        x0, x1, y0, y1 = self.bounds
        boundary = np.any((p[..., 0] < x0) | (p[..., 0] > x1) | (p[..., 1] < y0) | (p[..., 1] > y1), axis=1)
        if self.n_robots < 2:
            return np.zeros(self.n_swarms, dtype=bool), boundary
        s = self.rules.collision_shift
        shifted = p[..., :2] + s * np.stack((np.cos(p[..., 2]), np.sin(p[..., 2])), axis=-1)
        pairs = swarm_pairs(shifted, self.rules.collision_distance)
        collision = np.zeros(self.n_swarms, dtype=bool)
        collision[pairs[:, 0] // self.n_robots] = True
        return collision, boundary
