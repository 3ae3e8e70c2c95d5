"""The Robotarium's constants under the names rps uses (REFERENCE.md §1)."""
import numpy as np

from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.core.constants import COLLISION_DISTANCE, COLLISION_SHIFT, CONTROL_PERIOD
from swarmdeck.core.kinematics import GritsBotParams

_P = GritsBotParams()
time_step = CONTROL_PERIOD
robot_diameter = _P.diameter
wheel_radius = _P.wheel_radius
base_length = _P.axle_length
max_linear_velocity = _P.max_speed
max_angular_velocity = _P.max_angular_speed
max_wheel_velocity = _P.max_wheel_speed
#: rps: [x_min, y_min, width, height]
boundaries = np.array([DEFAULT_BOUNDS.x_min, DEFAULT_BOUNDS.y_min, DEFAULT_BOUNDS.width, DEFAULT_BOUNDS.height])
collision_offset = COLLISION_SHIFT
collision_diameter = COLLISION_DISTANCE
