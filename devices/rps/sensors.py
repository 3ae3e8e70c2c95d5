"""rps 2.0's sensor getters on the facade (REFERENCE.md §15; ``rps/robotarium_abc.py``), over the Arena's
:class:`~swarmdeck.sensing.Sensors`.

Shapes and behaviour as rps 2.0: ``get_distances()`` → ``(7, N)`` m (−1: nothing in range or dropped; NaN before
the first step, and always NaN without ``use_distance_sensors=True`` — rps 2.0 returns its NaN array then; the
facade also warns once, naming the flag), ``get_distance_endpoints()`` → ``(2, 7, N)`` (without
``use_distance_sensors=True`` rps 2.0 fails with an AttributeError: so does the facade, with a message naming the
flag), ``get_encoders()`` → ``(2, N)`` int32 counts [left; right] since the start, ``get_accelerations()`` →
``(3, N)`` m/s², ``get_gyros()`` → ``(3, N)`` rad/s, ``get_magnetic_fields()`` → ``(3, N)`` µT,
``get_orientations()`` → ``(N,)`` degrees in [0, 360). ``set_leds(ids, rgb)`` sets LEDs (``(3, len(ids))``,
0…255 or floats in [0, 1]); rps 2.0 keeps them in ``_leds`` ``(3, N)``.
"""
from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.constants import (
    ACCEL_NOISE,
    ENCODER_COUNTS_PER_REV,
    ENCODER_NOISE,
    GYRO_NOISE,
    IMU_OFFSET,
    MAG_NOISE,
    MAG_XY,
    MAG_Z,
    MOTOR_GEAR_RATIO,
    ORIENTATION_NOISE_DEG,
    TOF_BODY_OFFSET,
    TOF_DROPOUT,
    TOF_ERROR,
    TOF_OUTLIER,
    TOF_RANGE,
    TOF_SENSOR_POSES,
)
from swarmdeck.core.errors import SwarmdeckError
from swarmdeck.sensing import DistanceSensorConfig, SensingConfig, SensorReadings

__all__ = ["DISTANCE_FLAG_HINT", "RpsSensors", "SensorsDisabledError", "sensing_for"]

DISTANCE_FLAG_HINT = ("the distance sensors are off: create the Robotarium with use_distance_sensors=True "
                      "(rps 2.0's keyword) to simulate them")


class SensorsDisabledError(AttributeError, SwarmdeckError):
    """A distance-sensor getter rps 2.0 has only with ``use_distance_sensors=True`` was called without it."""


def sensing_for(use_distance_sensors: bool) -> SensingConfig:
    """The facade's sensors: rps 2.0's IMU, encoders and LEDs always; the ToF sensors when asked for."""
    if not isinstance(use_distance_sensors, bool):  # rps 2.0 asserts the type: name it
        raise TypeError(f"use_distance_sensors must be True or False, got {use_distance_sensors!r}")
    return SensingConfig(distance=DistanceSensorConfig() if use_distance_sensors else None)


class RpsSensors:
    """Mixin for the facade's ``Robotarium``: the 2.0 getters over ``self._arena.sense()``."""

    _arena: Any
    number_of_robots: int
    _distances_warned: bool = False

    # rps 2.0's sensor constants (rps/robotarium_abc.py; REFERENCE.md §15), read by its examples
    DISTANCE_SENSOR_ERROR = TOF_ERROR
    DISTANCE_SENSOR_DROPOUT_PROB = TOF_DROPOUT
    DISTANCE_SENSOR_OUTLIER_PROB = TOF_OUTLIER
    DISTANCE_SENSOR_RANGE = TOF_RANGE
    DISTANCE_SENSORS_ORIENTATION = np.array(TOF_SENSOR_POSES).T  # (3, 7) [x; y; heading]
    CENTER_OFFSET = TOF_BODY_OFFSET
    ENCODER_COUNTS_PER_REVOLUTION = ENCODER_COUNTS_PER_REV
    MOTOR_GEAR_RATIO = MOTOR_GEAR_RATIO
    IMU_ORIENTATION = np.array([IMU_OFFSET[0], IMU_OFFSET[1], 0.0])
    ENCODER_NOISE_STD = ENCODER_NOISE
    ACCELEROMETER_NOISE_STDS = np.array(ACCEL_NOISE)
    GYRO_NOISE_STDS = np.array(GYRO_NOISE)
    MAGNETOMETER_NOISE_STDS = np.array(MAG_NOISE)
    MAGNETOMETER_Z_AVG = MAG_Z
    MAGNETOMETER_XY_AVG = MAG_XY
    ORIENTATION_NOISE_STD = ORIENTATION_NOISE_DEG

    def _readings(self) -> SensorReadings:
        return self._arena.sense()

    @property
    def _distance_sensors_enabled(self) -> bool:
        """rps 2.0's flag."""
        return self._arena.sensors is not None and self._arena.sensors.config.distance is not None

    def get_distances(self) -> NDArray[np.float64]:
        """ToF readings ``(7, N)`` m (a copy): −1 nothing in range or dropped; NaN before the first step."""
        r = self._readings().distances
        if r is None:
            if not self._distances_warned:
                self._distances_warned = True
                warnings.warn(f"get_distances(): {DISTANCE_FLAG_HINT}; returning NaN as rps 2.0 does",
                              RuntimeWarning, stacklevel=2)
            return np.full((7, self.number_of_robots), np.nan)
        return np.array(r.T, dtype=float)

    def get_distance_endpoints(self) -> NDArray[np.float64]:
        """Where each reading ends, ``(2, 7, N)`` m; NaN where nothing was read."""
        e = self._readings().endpoints
        if e is None:
            if self._distance_sensors_enabled:  # before the first step
                return np.full((2, 7, self.number_of_robots), np.nan)
            raise SensorsDisabledError(f"get_distance_endpoints(): {DISTANCE_FLAG_HINT}")
        return np.array(np.transpose(e, (2, 1, 0)), dtype=float)

    def get_encoders(self) -> NDArray[np.int32]:
        """Encoder counts ``(2, N)`` int32, rows [left; right], since the start."""
        e = self._readings().encoders
        return np.zeros((2, self.number_of_robots), np.int32) if e is None else e.T.astype(np.int32)

    def get_accelerations(self) -> NDArray[np.float64]:
        """Accelerometer ``(3, N)`` m/s² (z reads −9.81 at rest)."""
        return self._column("accel", 3)

    def get_gyros(self) -> NDArray[np.float64]:
        """Gyro ``(3, N)`` rad/s."""
        return self._column("gyro", 3)

    def get_magnetic_fields(self) -> NDArray[np.float64]:
        """Magnetometer ``(3, N)`` µT."""
        return self._column("mag", 3)

    def get_orientations(self) -> NDArray[np.float64]:
        """Orientation ``(N,)`` degrees in [0, 360)."""
        o = self._readings().orientation
        return np.zeros(self.number_of_robots) if o is None else np.array(o, dtype=float)

    def _column(self, name: str, rows: int) -> NDArray[np.float64]:
        a = getattr(self._readings(), name)
        return np.zeros((rows, self.number_of_robots)) if a is None else np.array(a.T, dtype=float)

    def set_leds(self, ids: ArrayLike, rgb: ArrayLike) -> None:
        """Set the LEDs of robots ``ids`` to ``rgb`` ``(3, len(ids))`` (0…255, or floats in [0, 1])."""
        idx = np.atleast_1d(np.asarray(ids))
        colours = np.asarray(rgb)
        if colours.ndim == 1:
            colours = colours.reshape(3, -1)
        self._arena.set_leds(colours.T, ids=idx)

    @property
    def _leds(self) -> NDArray[np.float64]:
        """rps 2.0's ``(3, N)`` LED colours."""
        leds = self._readings().leds
        return np.zeros((3, self.number_of_robots)) if leds is None else leds.T.astype(float)
