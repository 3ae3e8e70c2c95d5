"""The Robotarium's constants under the names rps uses (REFERENCE.md §1)."""
import numpy as np

from swarmdeck.core.kinematics import GritsBotParams

_P = GritsBotParams()
time_step = 0.033
robot_diameter = _P.diameter
wheel_radius = _P.wheel_radius
base_length = _P.axle_length
max_linear_velocity = _P.max_speed
max_angular_velocity = _P.max_angular_speed
max_wheel_velocity = _P.max_wheel_speed
boundaries = np.array([-1.6, -1.0, 3.2, 2.0])  # rps: [x_min, y_min, width, height]
collision_offset = 0.025
collision_diameter = 0.135
