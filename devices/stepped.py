"""The experiment API's one adapter over the robot ports: poses now, one period per step.

:class:`SteppedRobots` turns any robot ports of :mod:`swarmdeck.core.ports` — a ``PoseSource``
and a ``CommandSink``, usually one object: the simulated robots, the MQTT robots, virtual robots
beside them, a fleet's assigned robots, the verification's disturbed simulator, the sandboxed
script's robots across the pipe — into what :class:`~swarmdeck.devices.arena.Arena` drives:
``poses`` ``(N, 3)`` in a fixed robot order, ``time`` (s since the start) and ``step(v, w)``,
which sends one unicycle command per robot and returns once the period is over.

The robots are the ones in the first reading, in its order (row k is robot ``ids[k]``); a robot
missing from a later reading (excluded by the MQTT link) keeps its last known pose. Time is the
robots' simulated clock when readings carry one (``SensedPoses.time``), else the monotonic clock,
and then every step is paced to one period of wall time (robots in the real world move in it).
"""
from __future__ import annotations

import time as _time
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.core.ports import (
    CommandSink,
    NominalSink,
    PoseSource,
    ReportsObstacles,
    ReportsValidation,
    SensedPoses,
    rows_of,
)
from swarmdeck.devices.clock import RealTimePacer

FloatArray = NDArray[np.float64]


class SteppedRobots:
    """Robot ports as the Arena's synchronous robots (module docstring).

    Args:
        source: where poses come from.
        sink: where commands go (default: ``source``, for ports that are both).
        params: the robot model.
        dt: the period one step lasts, s.
        clock: the monotonic clock for robots without a simulated clock.
        wait_for_poses: s to wait for a first finite pose of every robot (robots in the real world).

    Raises:
        ValueError: the ports give no robot, or some robots sent no pose within ``wait_for_poses``.
    """

    def __init__(self, source: PoseSource, sink: CommandSink | None = None, *, params: GritsBotParams,
                 dt: float, clock: Callable[[], float] = _time.monotonic, wait_for_poses: float = 5.0) -> None:
        self.source = source
        self.sink: Any = source if sink is None else sink
        self.params, self.dt, self.clock = params, float(dt), clock
        reading = source.read(0.0)
        deadline = clock() + wait_for_poses
        while reading.time is None and not np.all(np.isfinite(reading.poses)) and clock() < deadline:
            _time.sleep(0.02)
            reading = source.read(0.0)
        self.ids = np.asarray(reading.ids, dtype=np.int64).reshape(-1).copy()
        if not len(self.ids):
            raise ValueError(f"{getattr(source, 'name', 'the robots')}: no robot to drive")
        poses = np.asarray(reading.poses, dtype=float).reshape(-1, 3)
        missing = self.ids[~np.all(np.isfinite(poses), axis=1)]
        if len(missing):
            raise ValueError(f"no pose received for robot id(s) {missing.tolist()} within {wait_for_poses} s")
        self.n_robots = len(self.ids)
        self._last = poses.copy()
        self._reading = reading
        self.simulated = reading.time is not None
        self._t0 = float(reading.time) if reading.time is not None else clock()
        self._pacer = None if self.simulated else RealTimePacer(self.dt)
        # the ports' optional capabilities, checked once: isinstance on a runtime_checkable Protocol walks the
        # protocol's attributes at every call, and a port's class does not change while it drives the robots
        self._nominal_sink: NominalSink | None = self.sink if isinstance(self.sink, NominalSink) else None
        self._reports_obstacles = isinstance(self.sink, ReportsObstacles)

    def start_clock(self) -> None:
        """Time 0 is now (robots in the real world; a simulated clock keeps its first reading's time)."""
        if not self.simulated:
            self._t0 = self.clock()

    def read(self) -> SensedPoses:
        """A fresh reading of the ports (every robot of the first reading in its order is in ``poses``)."""
        reading = self.source.read(0.0)
        self._reading = reading
        ids = np.asarray(reading.ids, dtype=np.int64)
        if len(ids) == self.n_robots and ids.shape == self.ids.shape and bool((ids == self.ids).all()):
            p = np.asarray(reading.poses, dtype=float)
        else:  # robots left out of this reading keep their last known pose
            rows, have = rows_of(ids, self.ids)
            p = self._last.copy()
            p[have] = np.asarray(reading.poses, dtype=float)[rows[have]]
        ok = np.all(np.isfinite(p), axis=1)
        self._last = np.where(ok[:, None], p, self._last)
        return reading

    @property
    def poses(self) -> FloatArray:
        """Current poses ``(N, 3)`` ``[x, y, θ]`` (a copy; last known for robots gone silent)."""
        self.read()
        return self._last.copy()

    @property
    def time(self) -> float:
        """s since the start: the robots' simulated clock, or the monotonic clock for real robots."""
        if self.simulated:
            t = self.source.read(0.0).time
            return float(t) - self._t0 if self._t0 else float(t)  # type: ignore[arg-type]
        return self.clock() - self._t0

    @property
    def is_virtual(self) -> NDArray[np.bool_]:
        """``(N,)`` robots simulated beside physical ones (all False unless the ports say so)."""
        mask = self._reading.is_virtual
        return np.zeros(self.n_robots, dtype=bool) if mask is None else np.array(mask, dtype=bool)

    @property
    def nominal_sink(self) -> NominalSink | None:
        """The sink when it is behind a trust boundary (it takes nominal velocities), else None."""
        return self._nominal_sink

    def obstacles(self) -> FloatArray | None:
        """``(M, 2)`` fixed obstacles the sink knows (robots excluded from control, docked robots), m."""
        found = self.sink.obstacles() if self._reports_obstacles else None
        if found is None:
            return None
        obs = np.asarray(found, dtype=float).reshape(-1, 2)
        return obs if len(obs) else None

    def step(self, v: ArrayLike, w: ArrayLike) -> FloatArray:
        """Send ``(v, ω)`` ``(N,)`` each for one period; returns the new poses."""
        v = np.asarray(v, dtype=float).reshape(-1)
        w = np.asarray(w, dtype=float).reshape(-1)
        if v.shape != (self.n_robots,) or w.shape != (self.n_robots,):
            raise ValueError(f"v and w must each have shape ({self.n_robots},), got {v.shape} and {w.shape}")
        self.sink.send(self.ids, v, w)
        if self._pacer is not None:
            self._pacer.wait()
        return self.poses

    def step_nominal(self, nominal: ArrayLike) -> FloatArray:
        """Hand the nominal look-ahead velocities ``(N, 2)`` to a :class:`~swarmdeck.core.ports.NominalSink`."""
        sink = self.nominal_sink
        if sink is None:
            raise TypeError(f"{type(self.sink).__name__} takes unicycle commands, not nominal velocities")
        sink.send_nominal(self.ids, np.asarray(nominal, dtype=float))
        return self.poses

    @property
    def report(self) -> Any:
        """The robots' validation report (the simulator's counts), or None where nobody validates."""
        return self.sink.report if isinstance(self.sink, ReportsValidation) else None

    def close(self) -> None:
        """Stop the robots and release them (:func:`~swarmdeck.core.ports.close_ports`)."""
        from swarmdeck.core.ports import close_ports

        close_ports(self.source, self.sink)
