"""The Robotarium's numbers, each named once (REFERENCE.md §1 and §3); everything else uses these names.

Units: metres, seconds, radians. The robot's drive and body are gathered in
:class:`swarmdeck.core.kinematics.GritsBotParams`, whose defaults are these constants; the arena
rectangle is :data:`swarmdeck.core.bounds.DEFAULT_BOUNDS`.
"""
from __future__ import annotations

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
