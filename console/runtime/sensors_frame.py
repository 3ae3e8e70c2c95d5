"""What the robots sensed in one tick, as a Frame carries it (issue 28.1): :class:`SensorsFrame`.

Optional in a Frame (``Frame.sensors``), written only when present, so older recordings read as "no sensors".
It stores what cannot be derived — the ToF readings, the LEDs, the encoders and IMU — and derives the rays from the
Frame's poses with the sensing layer's own geometry (:func:`swarmdeck.sensing.sensor_rays`), so a drawing of a
recorded frame is the drawing of the live one. JSON layout (``Frame.to_dict()["sensors"]``; units m, rad)::

    sensor_poses  (K,3) [x, y, heading] of each ToF sensor on the body (its frame body_offset ahead of the axle)
    body_offset   float m
    distances     (N,K) m; −1 nothing in range or dropped, NaN not read yet        (only with ToF sensors)
    leds          (N,3) int 0…255 RGB                                              (only with LEDs)
    encoders      (N,2) int counts [left, right]                                   (only with an IMU)
    imu           (N,10) [accel x,y,z m/s², gyro x,y,z rad/s, mag x,y,z µT, orientation deg]  (only with an IMU)

The recording codec (format 2/3) packs the same keys as binary arrays: distances and imu float32, leds uint8,
encoders int32 (:meth:`SensorsFrame.packed` / :meth:`SensorsFrame.unpacked`).
"""
from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.sensing import DistanceSensorConfig, SensingConfig, SensorReadings, distance_endpoints, sensor_rays

__all__ = ["SensorsFrame"]

FloatArray = NDArray[np.float64]
_OPTIONAL = (("distances", "<f4", None), ("leds", "|u1", 3), ("encoders", "<i4", 2), ("imu", "<f4", 10))


def _ro(a: Any, dtype: Any) -> Any:
    if a is None:
        return None
    arr = np.array(a, dtype=dtype, copy=True)
    arr.flags.writeable = False
    return arr


@dataclass(frozen=True)
class SensorsFrame:
    """One tick's sensor readings (see the module docstring for shapes and units)."""

    sensor_poses: FloatArray
    body_offset: float = 0.0
    distances: FloatArray | None = None
    leds: NDArray[np.uint8] | None = None
    encoders: NDArray[np.int64] | None = None
    imu: FloatArray | None = None

    def __post_init__(self) -> None:
        poses = _ro(self.sensor_poses, float).reshape(-1, 3)
        object.__setattr__(self, "sensor_poses", poses)
        object.__setattr__(self, "body_offset", float(self.body_offset))
        k = len(poses)
        for name, dtype, width in (("distances", float, k), ("leds", np.uint8, 3), ("encoders", np.int64, 2),
                                   ("imu", float, 10)):
            arr = _ro(getattr(self, name), dtype)
            if arr is not None and (arr.ndim != 2 or arr.shape[1] != width):
                raise ValueError(f"frame field 'sensors.{name}' must have shape (n,{width}), got {arr.shape}")
            object.__setattr__(self, name, arr)

    @classmethod
    def of(cls, readings: SensorReadings, config: SensingConfig) -> SensorsFrame:
        """The Frame's view of :class:`~swarmdeck.sensing.SensorReadings` taken with ``config``."""
        tof = config.distance if config.distance is not None else DistanceSensorConfig()
        imu = None
        if readings.accel is not None and readings.gyro is not None and readings.mag is not None \
                and readings.orientation is not None:
            imu = np.column_stack((readings.accel, readings.gyro, readings.mag, readings.orientation))
        return cls(sensor_poses=tof.pose_array(), body_offset=tof.body_offset, distances=readings.distances,
                   leds=readings.leds, encoders=readings.encoders, imu=imu)

    def n_rows(self) -> int | None:
        """The number of robots the arrays have (None: only the sensor layout)."""
        for name, _, _ in _OPTIONAL:
            a = getattr(self, name)
            if a is not None:
                return int(a.shape[0])
        return None

    def _config(self) -> DistanceSensorConfig:
        poses = tuple((float(x), float(y), float(h)) for x, y, h in self.sensor_poses)
        reach = max((float(np.hypot(x, y)) for x, y, _ in poses), default=0.0)
        return DistanceSensorConfig(poses=poses, body_offset=self.body_offset,
                                    mount_radius=max(reach, DistanceSensorConfig().mount_radius))

    def rays(self, poses: FloatArray) -> tuple[FloatArray, FloatArray] | None:
        """The ToF rays at the Frame's ``poses`` ``(N, 3)``: origins and end points ``(N, K, 2)`` m (end points NaN
        where nothing was read), or None without distance readings."""
        if self.distances is None or len(self.sensor_poses) == 0:
            return None
        cfg = self._config()
        origins = sensor_rays(poses, cfg)[0]
        return origins, distance_endpoints(poses, self.distances, cfg)

    # ------------------------------------------------------------------ formats
    def to_dict(self, enc: Callable[[NDArray[Any]], list]) -> dict[str, Any]:
        """JSON-able dict (``enc``: the Frame's array encoder, writing NaN as a string)."""
        d: dict[str, Any] = {"sensor_poses": enc(self.sensor_poses), "body_offset": self.body_offset}
        for name, _, _ in _OPTIONAL:
            a = getattr(self, name)
            if a is not None:
                d[name] = enc(a)
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], dec: Callable[[Any, type, tuple[int, ...], str], NDArray[Any]]
                  ) -> SensorsFrame:
        """Inverse of :meth:`to_dict` (``dec``: the Frame's array decoder); ValueError naming the field."""
        if not isinstance(d, Mapping):
            raise ValueError(f"frame field 'sensors' must be an object, got {type(d).__name__}")
        poses = dec(d.get("sensor_poses", []), float, (3,), "sensors.sensor_poses")
        k = len(poses)
        kw: dict[str, Any] = {}
        for name, dtype, width in (("distances", float, k), ("leds", int, 3), ("encoders", int, 2), ("imu", float, 10)):
            if d.get(name) is not None:
                kw[name] = dec(d[name], dtype, (width,), f"sensors.{name}")
        return cls(sensor_poses=poses, body_offset=float(d.get("body_offset", 0.0)), **kw)

    def packed(self, pack: Callable[[NDArray[Any], str], dict[str, Any]]) -> dict[str, Any]:
        """The codec's form: binary arrays (``pack``: the codec's ``pack_array``)."""
        d: dict[str, Any] = {"sensor_poses": pack(self.sensor_poses, "<f8"), "body_offset": self.body_offset}
        for name, dtype, _ in _OPTIONAL:
            a = getattr(self, name)
            if a is not None:
                d[name] = pack(a, dtype)
        return d

    @classmethod
    def unpacked(cls, d: Mapping[str, Any], unpack: Callable[[Any, str], NDArray[Any]], n: int) -> SensorsFrame:
        """Inverse of :meth:`packed` for a frame of ``n`` robots; ValueError naming the field."""
        if not isinstance(d, Mapping):
            raise ValueError(f"frame field 'sensors' must be an object, got {type(d).__name__}")
        kw: dict[str, Any] = {}
        for name, _, _ in _OPTIONAL:
            if d.get(name) is not None:
                arr = unpack(d[name], f"sensors.{name}")
                if arr.ndim != 2 or arr.shape[0] != n:
                    raise ValueError(f"frame field 'sensors.{name}' must have {n} rows, got shape {arr.shape}")
                kw[name] = arr
        poses = unpack(d["sensor_poses"], "sensors.sensor_poses").astype(float)
        return cls(sensor_poses=poses, body_offset=float(d.get("body_offset", 0.0)), **kw)
