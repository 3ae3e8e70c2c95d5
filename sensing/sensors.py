"""A swarm's sensors on the trusted side: :class:`Sensors` keeps the state (encoder totals, last commands, LEDs)
and turns each step's poses and commands into one immutable :class:`SensorReadings`.

Used by :class:`swarmdeck.devices.Arena` (``Arena(..., sensing=SensingConfig(...))``), and through it by the rps
facade, the learning environments and the console; robots whose firmware reports readings hand them over through
:class:`swarmdeck.core.ports.ReportsSensors` instead.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.kinematics import GritsBotParams, UnicycleParams
from swarmdeck.sensing.config import SensingConfig, SensingConfigError
from swarmdeck.sensing.geometry import check_segments
from swarmdeck.sensing.models import (
    RangeBearing,
    check_sensing_poses,
    distances_along,
    encoders_and_imu,
    endpoints_along,
    noisy_distances,
    range_and_bearing,
    sensor_rays,
)

__all__ = ["SensorReadings", "Sensors", "check_leds"]

FloatArray = NDArray[np.float64]


def _frozen(a: NDArray[Any] | None) -> Any:
    if a is None:
        return None
    a = np.array(a, copy=True)
    a.flags.writeable = False
    return a


def _sealed(a: NDArray[Any] | None) -> Any:
    """``a`` made read-only in place: only for an array this module has just made and hands out (no copy)."""
    if a is not None:
        a.flags.writeable = False
    return a


def _finite_or_zero(values: ArrayLike, n: int) -> FloatArray:
    """``values`` as a new float ``(n,)`` array with NaN and ±inf replaced by 0 (``np.nan_to_num(..., nan=0.0,
    posinf=0.0, neginf=0.0)``, in fewer calls)."""
    a = np.asarray(values, dtype=float).reshape(n)
    return np.where(np.isfinite(a), a, 0.0)


@dataclass(frozen=True)
class SensorReadings:
    """What every robot sensed in one step (read-only arrays; None: that sensor is absent). Rows are robots.

    Attributes:
        distances: ``(N, K)`` ToF readings, m; −1 nothing in range or dropped.
        origins: ``(N, K, 2)`` where each sensor's ray starts, m.
        endpoints: ``(N, K, 2)`` where each reading ends, m; NaN for −1.
        encoders: ``(N, 2)`` int64 counts [left, right] since the start.
        accel: ``(N, 3)`` m/s²; gyro ``(N, 3)`` rad/s; mag ``(N, 3)`` µT; orientation ``(N,)`` degrees in [0, 360).
        range_bearing: neighbours' ranges and bearings (:class:`~swarmdeck.sensing.models.RangeBearing`).
        leds: ``(N, 3)`` uint8 RGB of each robot's LED.
    """

    distances: FloatArray | None = None
    origins: FloatArray | None = None
    endpoints: FloatArray | None = None
    encoders: NDArray[np.int64] | None = None
    accel: FloatArray | None = None
    gyro: FloatArray | None = None
    mag: FloatArray | None = None
    orientation: FloatArray | None = None
    range_bearing: RangeBearing | None = None
    leds: NDArray[np.uint8] | None = None

    def robot(self, i: int) -> dict[str, Any]:
        """Robot ``i``'s own readings only (what its controller may see in a decentralised experiment): each
        present sensor's row as a copy, and ``neighbours`` {j: (range m, bearing rad)}."""
        out: dict[str, Any] = {}
        for name in ("distances", "encoders", "accel", "gyro", "mag", "orientation", "leds"):
            value = getattr(self, name)
            if value is not None:
                out[name] = np.array(value[i], copy=True)
        if self.range_bearing is not None:
            js, rs, bs = self.range_bearing.of(int(i))
            out["neighbours"] = {int(j): (float(r), float(b)) for j, r, b in zip(js, rs, bs)}
        return out


def check_leds(rgb: ArrayLike, rows: int) -> NDArray[np.uint8]:
    """``rgb`` as ``(rows, 3)`` uint8 (whole numbers 0…255; floats in [0, 1] are rps's colours, scaled);
    raises :class:`SensingConfigError` naming what is wrong."""
    arr = np.asarray(rgb)
    if arr.dtype.kind not in "fiu" or arr.dtype == bool:
        raise SensingConfigError(f"LED colours must be numbers (R, G, B), got dtype {arr.dtype}")
    if arr.shape != (rows, 3):
        raise SensingConfigError(f"LED colours must have shape ({rows}, 3) [R, G, B], got {arr.shape}")
    a = arr.astype(float)
    if not np.isfinite(a).all() or (a < 0).any() or (a > 255).any():
        raise SensingConfigError("LED colours must be finite and in [0, 255] (or [0, 1] floats)")
    if arr.dtype.kind == "f" and a.max(initial=0.0) <= 1.0:
        a = a * 255.0
    return np.rint(a).astype(np.uint8)


class Sensors:
    """The sensors of N robots: call :meth:`update` once per step, after the robots moved.

    Args:
        n: number of robots.
        config: which sensors and their noise.
        rng: the one source of noise (seeded by the caller).
        params: the robots' drive (wheel radius, axle length) for the encoders.
        bounds: the arena, for walls (``DistanceSensorConfig.walls``).
        obstacles: ``(M, 2, 2)`` obstacle segments, m.
    """

    def __init__(self, n: int, config: SensingConfig, *, rng: np.random.Generator,
                 params: UnicycleParams | None = None, bounds: Bounds | tuple[float, float, float, float] = DEFAULT_BOUNDS,
                 obstacles: ArrayLike | None = None) -> None:
        if not isinstance(config, SensingConfig):
            raise SensingConfigError(f"sensing must be a SensingConfig, got {config!r}")
        if not isinstance(rng, np.random.Generator):
            raise SensingConfigError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
        self.n = int(n)
        self.config = config
        self.rng = rng
        self.params = params if params is not None else GritsBotParams()
        self.bounds = Bounds.of(bounds)
        self.obstacles = check_segments(obstacles)
        self.obstacles.flags.writeable = False
        self._encoders = np.zeros((self.n, 2))
        self._v_prev = np.zeros(self.n)
        self._w_prev = np.zeros(self.n)
        self._leds = np.zeros((self.n, 3), dtype=np.uint8)
        self.readings: SensorReadings | None = None

    def with_leds(self, readings: SensorReadings) -> SensorReadings:
        """``readings`` with the LEDs as set now (LEDs change between steps; the rest is what was sensed)."""
        return replace(readings, leds=self.leds if self.config.leds else None)

    def set_leds(self, rgb: ArrayLike, ids: ArrayLike | None = None) -> None:
        """Set the LEDs: ``(N, 3)`` (or ``(len(ids), 3)``) RGB 0…255; shown from the next readings on."""
        if not self.config.leds:
            raise SensingConfigError("this swarm has no LEDs (SensingConfig(leds=False))")
        if ids is None:
            self._leds = check_leds(rgb, self.n)
            return
        idx = np.atleast_1d(np.asarray(ids))
        if idx.dtype.kind not in "iu" or ((idx < 0) | (idx >= self.n)).any():
            raise SensingConfigError(f"LED ids must be robot indices 0..{self.n - 1}, got {idx.tolist()!r}")
        leds = self._leds.copy()
        leds[idx] = check_leds(rgb, len(idx))
        self._leds = leds

    @property
    def leds(self) -> NDArray[np.uint8]:
        """The LEDs' ``(N, 3)`` RGB as set now (a read-only copy)."""
        return _frozen(self._leds)

    def first(self, poses: ArrayLike) -> SensorReadings:
        """The readings before the first step: distances NaN (as rps 2.0), encoders 0, the robots at rest."""
        p = check_sensing_poses(poses)
        k = self.config.distance.n_sensors if self.config.distance is not None else 0
        readings = self._assemble(p, np.zeros(self.n), np.zeros(self.n), 1.0,
                                  distances=np.full((self.n, k), np.nan) if self.config.distance else None)
        return readings

    def update(self, poses: ArrayLike, v: ArrayLike, w: ArrayLike, dt: float) -> SensorReadings:
        """The readings after a step of ``dt`` s in which the robots ran ``v`` (m/s), ``w`` (rad/s) ``(N,)`` and
        arrived at ``poses`` ``(N, 3)``."""
        p = check_sensing_poses(poses)
        if len(p) != self.n:
            raise SensingConfigError(f"poses has {len(p)} robots, the sensors {self.n}")
        vv = _finite_or_zero(v, self.n)
        ww = _finite_or_zero(w, self.n)
        distances = rays = None
        cfg = self.config.distance
        if cfg is not None:
            rays = sensor_rays(p, cfg)  # once: the casts, the origins and the endpoints
            true = (distances_along(p, rays[0], rays[1], cfg, self.obstacles, self.bounds) if self.n
                    else np.empty((0, cfg.n_sensors)))
            distances = noisy_distances(true, cfg, self.rng)
        readings = self._assemble(p, vv, ww, float(dt), distances=distances, rays=rays, step=True)
        self._v_prev, self._w_prev = vv, ww
        return readings

    def _assemble(self, p: FloatArray, v: FloatArray, w: FloatArray, dt: float, *, distances: FloatArray | None,
                  rays: tuple[FloatArray, FloatArray] | None = None, step: bool = False) -> SensorReadings:
        cfg = self.config
        origins = endpoints = None
        if cfg.distance is not None and distances is not None:
            origins, directions = rays if rays is not None else sensor_rays(p, cfg.distance)
            endpoints = endpoints_along(origins, directions, distances)
        encoders = accel = gyro = mag = orientation = None
        if cfg.imu is not None:
            increment, imu = encoders_and_imu(v, w, self._v_prev if step else v, self._w_prev if step else w, p[:, 2],
                                              dt, self.params, cfg.imu, self.rng, encoders=step)
            if increment is not None:
                self._encoders = self._encoders + increment
            encoders = self._encoders.astype(np.int64)
            accel, gyro, mag, orientation = imu.accel, imu.gyro, imu.mag, imu.orientation
        rb = range_and_bearing(p, cfg.range_bearing, self.rng) if cfg.range_bearing is not None else None
        if rb is not None:
            rb = RangeBearing(*(_sealed(a) for a in (rb.i, rb.j, rb.range, rb.bearing)))
        # every array below was made for these readings alone: read-only in place, no copies
        self.readings = SensorReadings(
            distances=_sealed(distances), origins=_sealed(origins), endpoints=_sealed(endpoints),
            encoders=_sealed(encoders), accel=_sealed(accel), gyro=_sealed(gyro), mag=_sealed(mag),
            orientation=_sealed(orientation), range_bearing=rb, leds=_frozen(self._leds) if cfg.leds else None)
        return self.readings
