"""What robots sense (issue 28.1): ToF distance sensors, range and bearing to neighbours, wheel encoders, the IMU
and an RGB LED per robot — one vectorised layer on the trusted side, seeded noise, exact geometry.

Defaults are Robotarium 2.0's (REFERENCE.md §15). :class:`Sensors` holds a swarm's sensor state and makes one
:class:`SensorReadings` per step; the pure functions (:func:`cast_rays`, :func:`true_distances`,
:func:`noisy_distances`, :func:`range_and_bearing`, :func:`encoder_increment`, :func:`imu_readings`) are what it is
made of. Imports only :mod:`swarmdeck.core` (and numpy, scipy).
"""
from swarmdeck.sensing.config import (
    DistanceSensorConfig,
    ImuConfig,
    RangeBearingConfig,
    SensingConfig,
    SensingConfigError,
)
from swarmdeck.sensing.geometry import cast_rays, check_segments
from swarmdeck.sensing.models import (
    ImuReadings,
    RangeBearing,
    distance_endpoints,
    encoder_increment,
    imu_readings,
    noisy_distances,
    range_and_bearing,
    sensor_rays,
    true_distances,
)
from swarmdeck.sensing.sensors import SensorReadings, Sensors, check_leds

__all__ = ["DistanceSensorConfig", "ImuConfig", "ImuReadings", "RangeBearing", "RangeBearingConfig", "SensingConfig",
           "SensingConfigError", "SensorReadings", "Sensors", "cast_rays", "check_leds", "check_segments",
           "distance_endpoints", "encoder_increment", "imu_readings", "noisy_distances", "range_and_bearing",
           "sensor_rays", "true_distances"]
