"""The Robotarium's numbers, each named once (REFERENCE.md §1 and §3); everything else uses these names.

Units: metres, seconds, radians. The robot's drive and body are gathered in
:class:`swarmdeck.core.kinematics.GritsBotParams`, whose defaults are these constants; the arena
rectangle is :data:`swarmdeck.core.bounds.DEFAULT_BOUNDS`.
"""
from __future__ import annotations

import math

#: Control (camera) period, s: ~30 Hz (REFERENCE.md §1).
CONTROL_PERIOD: float = 0.033

#: GRITSBot body diameter, m (REFERENCE.md §1); two bodies touch when their centres are this close.
ROBOT_DIAMETER: float = 0.11
#: GRITSBot body radius, m: half of :data:`ROBOT_DIAMETER` (0.055, exactly the literal's double).
ROBOT_RADIUS: float = ROBOT_DIAMETER / 2
#: Wheel radius r, m (REFERENCE.md §1).
WHEEL_RADIUS: float = 0.016
#: Axle (base) length L between the wheels, m (REFERENCE.md §1).
AXLE_LENGTH: float = 0.105
#: Largest wheel angular speed, rad/s: 0.2 / 0.016 (REFERENCE.md §1).
MAX_WHEEL_SPEED: float = 12.5
#: Largest linear speed, m/s (REFERENCE.md §1).
MAX_LINEAR_SPEED: float = 0.2
#: swarmdeck's look-ahead ℓ of the near-identity diffeomorphism, m (REFERENCE.md §1: 0.03–0.05).
LOOKAHEAD: float = 0.03

#: D_s, the barrier's safety distance between controlled (look-ahead) points, m (REFERENCE.md §3: rps's
#: single-integrator default; with ℓ = 0.03 it is Ø 0.11 + 2ℓ, so bodies whose points keep it never touch).
SAFETY_DISTANCE: float = 0.17

#: rps validator: collision centres are shifted this far forward along the heading, m (REFERENCE.md §1).
COLLISION_SHIFT: float = 0.025
#: rps validator: two robots collide when their shifted centres are at most this far apart, m (REFERENCE.md §1).
COLLISION_DISTANCE: float = 0.135

# ---------------------------------------------------------------- the GTernal (Robotarium 2.x, REFERENCE.md §15)
#: GTernal base (axle) length L, m (REFERENCE.md §15; rps 2.x ``ARobotarium.BASE_LENGTH``). Its diameter (0.11 m),
#: wheel radius (0.016 m), top speed (0.2 m/s), collision diameter and offset are the GRITSBot's numbers above.
GTERNAL_BASE_LENGTH: float = 0.11
#: rps 2.x's limit on the robots of one simulation (REFERENCE.md §1, §15: ``0 <= number_of_robots <= 50``).
RPS_MAX_ROBOTS: int = 50
# ---------------------------------------------------------------- Robotarium 2.0's sensors (REFERENCE.md §15)
# (rps/robotarium_abc.py of robotarium/robotarium_python_simulator 2.0; swarmdeck.sensing takes its defaults here)
#: The seven ToF distance sensors' poses on the body, ``(x, y, heading)`` in m, m, rad, in the body frame centred
#: :data:`TOF_BODY_OFFSET` ahead of the axle (x forward, y left) (REFERENCE.md §15).
TOF_SENSOR_POSES: tuple[tuple[float, float, float], ...] = (
    (-0.04, 0.04, math.pi), (0.0, 0.06, math.pi / 2), (0.04, 0.05, math.pi / 4), (0.05, 0.0, 0.0),
    (0.04, -0.05, -math.pi / 4), (0.0, -0.06, -math.pi / 2), (-0.04, -0.04, -math.pi))
#: ToF range, m (REFERENCE.md §15): nothing farther is seen.
TOF_RANGE: float = 1.2
#: ToF error, the fractional standard deviation σ/d of a reading (REFERENCE.md §15).
TOF_ERROR: float = 0.03
#: Probability that a ToF reading of something in range is dropped (reads −1) (REFERENCE.md §15).
TOF_DROPOUT: float = 0.035
#: Probability that a kept ToF reading is an outlier, uniform on [0, range] (REFERENCE.md §15).
TOF_OUTLIER: float = 0.014
#: rps 2.0's CENTER_OFFSET, m: the body circle (and the sensors' frame) sits this far ahead of the axle.
TOF_BODY_OFFSET: float = 0.01
#: Wheel encoder counts per motor revolution (REFERENCE.md §15).
ENCODER_COUNTS_PER_REV: int = 28
#: Motor gear ratio: motor revolutions per wheel revolution (REFERENCE.md §15).
MOTOR_GEAR_RATIO: float = 100.37
#: Encoder noise σ, counts per √count of a step (at least one count) (REFERENCE.md §15).
ENCODER_NOISE: float = 0.25
#: Accelerometer noise σ (x, y, z), m/s² (REFERENCE.md §15).
ACCEL_NOISE: tuple[float, float, float] = (0.012929, 0.012127, 0.052979)
#: Gyro noise σ (x, y, z), rad/s (REFERENCE.md §15).
GYRO_NOISE: tuple[float, float, float] = (0.001663, 0.001216, 0.002372)
#: Magnetometer noise σ (x, y, z), µT (REFERENCE.md §15).
MAG_NOISE: tuple[float, float, float] = (3.275843, 2.365798, 5.232685)
#: Mean horizontal magnetic field, µT (REFERENCE.md §15: xy 6.07 µT).
MAG_XY: float = 6.0712
#: Mean vertical magnetic field, µT (REFERENCE.md §15: z −39.86 µT).
MAG_Z: float = -39.8594
#: Orientation noise σ, degrees (REFERENCE.md §15).
ORIENTATION_NOISE_DEG: float = 0.310830
#: The IMU's position on the body (x, y) from the axle centre, m (rps 2.0 IMU_ORIENTATION).
IMU_OFFSET: tuple[float, float] = (0.0594 - 0.00319, 0.0344628 - 0.0475)
#: Standard gravity, m/s² (the accelerometer's z reads −g at rest).
GRAVITY: float = 9.81
