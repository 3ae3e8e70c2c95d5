"""What the robots sense and how noisy it is: frozen configuration, defaults from Robotarium 2.0 (REFERENCE.md §15).

Every value is checked in ``__post_init__``; a bad one raises :class:`SensingConfigError` (a ``ValueError``)
naming the field, the allowed range and the value given. Units: m, rad, s; the magnetometer in µT, the
orientation noise in degrees.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.checks import require_in_range
from swarmdeck.core.constants import (
    ACCEL_NOISE,
    COLLISION_DISTANCE,
    ENCODER_COUNTS_PER_REV,
    ENCODER_NOISE,
    GYRO_NOISE,
    IMU_OFFSET,
    MAG_NOISE,
    MAG_XY,
    MAG_Z,
    MOTOR_GEAR_RATIO,
    ORIENTATION_NOISE_DEG,
    ROBOT_RADIUS,
    TOF_BODY_OFFSET,
    TOF_DROPOUT,
    TOF_ERROR,
    TOF_OUTLIER,
    TOF_RANGE,
    TOF_SENSOR_POSES,
)
from swarmdeck.core.errors import SwarmdeckError

__all__ = ["DistanceSensorConfig", "ImuConfig", "RangeBearingConfig", "SensingConfig", "SensingConfigError"]


class SensingConfigError(ValueError, SwarmdeckError):
    """A sensing configuration value is out of range; the message names the field."""


def _check(value: object, name: str, lo: float = -math.inf, hi: float = math.inf, *, unit: str = "",
           lo_open: bool = False, integer: bool = False) -> None:
    require_in_range(value, name, lo, hi, unit=unit, lo_open=lo_open, integer=integer, error=SensingConfigError)


def _triple(value: object, name: str) -> None:
    if not isinstance(value, tuple) or len(value) != 3:
        raise SensingConfigError(f"{name} must be a tuple of 3 numbers (x, y, z), got {value!r}")
    for k, v in enumerate(value):
        _check(v, f"{name}[{k}]", 0.0)


@dataclass(frozen=True)
class DistanceSensorConfig:
    """The ToF distance sensors (REFERENCE.md §15; rps 2.0's ``simulate_distance_sensors``).

    Attributes:
        poses: ``K`` sensor poses ``(x, y, heading)`` (m, m, rad) in the body frame centred ``body_offset`` ahead
            of the axle (x forward, y left). Each sensor must sit on the robot: within ``mount_radius`` of that centre.
        max_range: range, m (> 0): farther hits read −1.
        error: σ of a reading as a fraction of the true distance (≥ 0).
        dropout: probability that a reading of something in range reads −1, in [0, 1].
        outlier: probability that a kept reading is uniform on [0, max_range], in [0, 1].
        body_radius: radius of the circle every robot's body is for the rays, m (> 0).
        body_offset: how far ahead of the axle the body circle and the sensors' frame are centred, m.
        mount_radius: the robot's footprint for the sensors' mounts, m: the Robotarium's collision circle
            (Ø :data:`~swarmdeck.core.constants.COLLISION_DISTANCE`; the GTernal's sensors sit up to 0.064 m out).
        walls: True: the arena's walls stop rays too. rps 2.0 (and so the default): they do not (the floor is open).
    """

    poses: tuple[tuple[float, float, float], ...] = TOF_SENSOR_POSES
    max_range: float = TOF_RANGE
    error: float = TOF_ERROR
    dropout: float = TOF_DROPOUT
    outlier: float = TOF_OUTLIER
    body_radius: float = ROBOT_RADIUS
    body_offset: float = TOF_BODY_OFFSET
    mount_radius: float = COLLISION_DISTANCE / 2
    walls: bool = False

    def __post_init__(self) -> None:
        _check(self.max_range, "DistanceSensorConfig.max_range", 0.0, unit="m", lo_open=True)
        _check(self.error, "DistanceSensorConfig.error", 0.0, 1.0)
        _check(self.dropout, "DistanceSensorConfig.dropout", 0.0, 1.0)
        _check(self.outlier, "DistanceSensorConfig.outlier", 0.0, 1.0)
        _check(self.body_radius, "DistanceSensorConfig.body_radius", 0.0, unit="m", lo_open=True)
        _check(self.body_offset, "DistanceSensorConfig.body_offset", -self.body_radius, self.body_radius, unit="m")
        _check(self.mount_radius, "DistanceSensorConfig.mount_radius", 0.0, unit="m", lo_open=True)
        if not isinstance(self.walls, bool):
            raise SensingConfigError(f"DistanceSensorConfig.walls must be True or False, got {self.walls!r}")
        if not isinstance(self.poses, tuple) or not self.poses:
            raise SensingConfigError(f"DistanceSensorConfig.poses must be a non-empty tuple of (x, y, heading), "
                                     f"got {self.poses!r}")
        for k, pose in enumerate(self.poses):
            if not isinstance(pose, tuple) or len(pose) != 3:
                raise SensingConfigError(f"DistanceSensorConfig.poses[{k}] must be (x, y, heading), got {pose!r}")
            for c, name in zip(pose, ("x", "y", "heading")):
                _check(c, f"DistanceSensorConfig.poses[{k}].{name}")
            reach = math.hypot(pose[0], pose[1])
            if reach > self.mount_radius + 1e-12:
                raise SensingConfigError(
                    f"DistanceSensorConfig.poses[{k}] = {pose!r} is outside the body: {reach:.4f} m from its centre, "
                    f"the sensors' mount radius is {self.mount_radius} m")

    @property
    def n_sensors(self) -> int:
        """K, the number of sensors per robot."""
        return len(self.poses)

    def pose_array(self) -> NDArray[np.float64]:
        """The sensor poses as a read-only ``(K, 3)`` array."""
        arr = np.array(self.poses, dtype=float).reshape(-1, 3)
        arr.flags.writeable = False
        return arr


@dataclass(frozen=True)
class RangeBearingConfig:
    """Range and bearing to the neighbours (the GRITSBot's infrared abstraction; paper §III-D).

    Attributes:
        radius: neighbours within this centre distance are measured, m (> 0).
        range_sigma: Gaussian σ of a range, m (≥ 0).
        bearing_sigma: Gaussian σ of a bearing, rad (≥ 0).
        fov: the field of view centred on the heading, rad, in (0, 2π]; 2π sees all around.
        dropout: probability that one measurement is missing, in [0, 1].
    """

    radius: float = 0.5
    range_sigma: float = 0.005
    bearing_sigma: float = 0.02
    fov: float = 2 * math.pi
    dropout: float = 0.0

    def __post_init__(self) -> None:
        _check(self.radius, "RangeBearingConfig.radius", 0.0, unit="m", lo_open=True)
        _check(self.range_sigma, "RangeBearingConfig.range_sigma", 0.0, unit="m")
        _check(self.bearing_sigma, "RangeBearingConfig.bearing_sigma", 0.0, unit="rad")
        _check(self.fov, "RangeBearingConfig.fov", 0.0, 2 * math.pi, unit="rad", lo_open=True)
        _check(self.dropout, "RangeBearingConfig.dropout", 0.0, 1.0)


@dataclass(frozen=True)
class ImuConfig:
    """Wheel encoders, accelerometer, gyro, magnetometer and orientation (REFERENCE.md §15, rps 2.0's models).

    Attributes:
        counts_per_rev: encoder counts per motor revolution (integer > 0).
        gear_ratio: motor revolutions per wheel revolution (> 0).
        encoder_sigma: encoder noise, counts per √(counts of the step), at least one count (≥ 0).
        accel_sigma, gyro_sigma, mag_sigma: per-axis σ (x, y, z) in m/s², rad/s, µT (≥ 0).
        mag_xy, mag_z: the mean magnetic field's horizontal and vertical parts, µT.
        orientation_sigma_deg: σ of the orientation reading, degrees (≥ 0).
        imu_offset: the IMU's (x, y) on the body from the axle centre, m.
    """

    counts_per_rev: int = ENCODER_COUNTS_PER_REV
    gear_ratio: float = MOTOR_GEAR_RATIO
    encoder_sigma: float = ENCODER_NOISE
    accel_sigma: tuple[float, float, float] = ACCEL_NOISE
    gyro_sigma: tuple[float, float, float] = GYRO_NOISE
    mag_sigma: tuple[float, float, float] = MAG_NOISE
    mag_xy: float = MAG_XY
    mag_z: float = MAG_Z
    orientation_sigma_deg: float = ORIENTATION_NOISE_DEG
    imu_offset: tuple[float, float] = IMU_OFFSET

    def __post_init__(self) -> None:
        _check(self.counts_per_rev, "ImuConfig.counts_per_rev", 1, integer=True)
        _check(self.gear_ratio, "ImuConfig.gear_ratio", 0.0, lo_open=True)
        _check(self.encoder_sigma, "ImuConfig.encoder_sigma", 0.0, unit="counts")
        _triple(self.accel_sigma, "ImuConfig.accel_sigma")
        _triple(self.gyro_sigma, "ImuConfig.gyro_sigma")
        _triple(self.mag_sigma, "ImuConfig.mag_sigma")
        _check(self.mag_xy, "ImuConfig.mag_xy", unit="µT")
        _check(self.mag_z, "ImuConfig.mag_z", unit="µT")
        _check(self.orientation_sigma_deg, "ImuConfig.orientation_sigma_deg", 0.0, unit="deg")
        if not isinstance(self.imu_offset, tuple) or len(self.imu_offset) != 2:
            raise SensingConfigError(f"ImuConfig.imu_offset must be (x, y) in m, got {self.imu_offset!r}")
        for k, v in enumerate(self.imu_offset):
            _check(v, f"ImuConfig.imu_offset[{k}]", unit="m")

    @property
    def counts_per_radian(self) -> float:
        """Encoder counts per radian the wheel turns: counts_per_rev · gear_ratio / 2π."""
        return self.counts_per_rev * self.gear_ratio / (2 * math.pi)


@dataclass(frozen=True)
class SensingConfig:
    """Which sensors a swarm has (None: that sensor is absent).

    Attributes:
        distance: the ToF distance sensors (None by default, as rps 2.0's ``use_distance_sensors=False``).
        range_bearing: range and bearing to neighbours (None by default).
        imu: encoders, accelerometer, gyro, magnetometer, orientation (on by default, as on every GTernal).
        leds: an RGB LED per robot the experiment can set.
    """

    distance: DistanceSensorConfig | None = None
    range_bearing: RangeBearingConfig | None = None
    imu: ImuConfig | None = field(default_factory=ImuConfig)
    leds: bool = True

    def __post_init__(self) -> None:
        for name, kind in (("distance", DistanceSensorConfig), ("range_bearing", RangeBearingConfig),
                           ("imu", ImuConfig)):
            value = getattr(self, name)
            if value is not None and not isinstance(value, kind):
                raise SensingConfigError(f"SensingConfig.{name} must be a {kind.__name__} or None, got {value!r}")
        if not isinstance(self.leds, bool):
            raise SensingConfigError(f"SensingConfig.leds must be True or False, got {self.leds!r}")
