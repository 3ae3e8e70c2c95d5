# An rps example script (the Robotarium's "go to goal points with SI barriers"), unchanged in style.
import rps.robotarium as robotarium
from rps.utilities.transformations import *
from rps.utilities.barrier_certificates import *
from rps.utilities.misc import *
from rps.utilities.controllers import *

import numpy as np

N = 5
initial_conditions = generate_initial_conditions(N)
r = robotarium.Robotarium(number_of_robots=N, show_figure=False, initial_conditions=initial_conditions, sim_in_real_time=True)

goal_points = generate_initial_conditions(N, width=r.boundaries[2] - 0.6, height=r.boundaries[3] - 0.6, spacing=0.5)

single_integrator_position_controller = create_si_position_controller()
si_barrier_cert = create_single_integrator_barrier_certificate_with_boundary()
si_to_uni_dyn, uni_to_si_states = create_si_to_uni_mapping()

x = r.get_poses()
x_si = uni_to_si_states(x)
r.step()

while np.size(at_pose(np.vstack((x_si, x[2, :])), goal_points, rotation_error=100)) != N:
    x = r.get_poses()
    x_si = uni_to_si_states(x)
    dxi = single_integrator_position_controller(x_si, goal_points[:2][:])
    dxi = si_barrier_cert(dxi, x_si)
    dxu = si_to_uni_dyn(dxi, x)
    r.set_velocities(np.arange(N), dxu)
    r.step()

r.call_at_scripts_end()
