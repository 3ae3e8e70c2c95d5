# An rps-style script (numpy 1 idioms): go to points with the backwards-motion heading map, until
# every robot is within 5 cm of its goal. Initial conditions come from np.mat, as in rps's examples.
import numpy as np

import rps.robotarium as robotarium
from rps.utilities.barrier_certificates import *
from rps.utilities.controllers import *
from rps.utilities.misc import *
from rps.utilities.transformations import *

N = 4
initial_conditions = np.array(np.mat('1.0 -1.0 0.5 -0.5; 0.6 -0.6 -0.5 0.5; 0 3.14 1.57 -1.57'))
r = robotarium.Robotarium(number_of_robots=N, show_figure=False, initial_conditions=initial_conditions,
                          sim_in_real_time=False)
goals = np.array([[-1.0, 1.0, -0.5, 0.5], [0.6, -0.6, 0.5, -0.5]])  # each robot crosses the arena
controller = create_si_position_controller()
barrier = create_single_integrator_barrier_certificate_with_boundary()
si_to_uni = create_si_to_uni_dynamics_with_backwards_motion()

x = r.get_poses()
r.step()
while np.size(at_position(x[:2], goals, position_error=0.05)) != N:
    x = r.get_poses()
    dxi = barrier(controller(x[:2], goals), x[:2])
    r.set_velocities(np.arange(N), si_to_uni(dxi, x))
    r.step()
r.call_at_scripts_end()
