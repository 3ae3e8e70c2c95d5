"""rps's ``robotarium_abc``: the 1.x module constants (the GRITSBot) and rps 2.x's ``ARobotarium`` class constants
(the GTernal, REFERENCE.md §15), for scripts that read them."""
import numpy as np

from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.core.constants import COLLISION_DISTANCE, COLLISION_SHIFT, CONTROL_PERIOD, RPS_MAX_ROBOTS
from swarmdeck.core.robot_models import robot_params
from swarmdeck.devices.robotarium_constants import *  # noqa: F401,F403

_GTERNAL = robot_params("gternal")


class ARobotarium:
    """rps 2.x's base class, as far as scripts read it: the GTernal's constants under rps 2.x's names (SI units;
    ``BOUNDARIES`` is ``[x_min, x_max, y_min, y_max]``). :class:`~swarmdeck.devices.rps.robotarium.Robotarium`
    derives from it and sets the same names on each instance for the robot model it runs."""

    TIME_STEP = CONTROL_PERIOD
    MAX_LINEAR_VELOCITY = _GTERNAL.max_speed
    ROBOT_DIAMETER = _GTERNAL.diameter
    WHEEL_RADIUS = _GTERNAL.wheel_radius
    BASE_LENGTH = _GTERNAL.axle_length
    COLLISION_DIAMETER = COLLISION_DISTANCE
    COLLISION_OFFSET = COLLISION_SHIFT
    BOUNDARIES = np.array([DEFAULT_BOUNDS.x_min, DEFAULT_BOUNDS.x_max, DEFAULT_BOUNDS.y_min, DEFAULT_BOUNDS.y_max])
    MAX_WHEEL_VELOCITY = _GTERNAL.max_wheel_speed
    MAX_ANGULAR_VELOCITY = _GTERNAL.max_angular_speed
    MAX_ROBOTS = RPS_MAX_ROBOTS
