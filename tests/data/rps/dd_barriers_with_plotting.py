# An rps-style script: unicycle go-to-point through the differential-drive barrier (with the
# boundary), drawing goals and captions on r.axes as rps's plotting examples do.
import numpy as np

import rps.robotarium as robotarium
from rps.utilities.barrier_certificates import *
from rps.utilities.controllers import *
from rps.utilities.misc import *
from rps.utilities.transformations import *

N = 4
initial_conditions = np.array([[-1.0, 1.0, 0.0, 0.0], [0.0, 0.0, -0.7, 0.7], [0.0, np.pi, np.pi / 2, -np.pi / 2]])
r = robotarium.Robotarium(number_of_robots=N, show_figure=True, initial_conditions=initial_conditions,
                          sim_in_real_time=True)
goals = np.array([[1.0, -1.0, 0.0, 0.0], [0.0, 0.0, 0.7, -0.7]])  # swap through the centre
size = determine_marker_size(r, 0.1)
markers = [r.axes.scatter(goals[0, i], goals[1, i], s=size, marker='s') for i in range(N)]
captions = [r.axes.text(goals[0, i], goals[1, i], f"G{i}", fontsize=determine_font_size(r, 0.1)) for i in range(N)]
r.axes.imshow(np.zeros((8, 8, 3)), extent=(-0.2, 0.2, -0.2, 0.2))
plt.title(f"robots of diameter {r.robot_diameter} m")
controller = create_clf_unicycle_position_controller()
barrier = create_unicycle_differential_drive_barrier_certificate_with_boundary()

x = r.get_poses()
r.step()
for _ in range(900):
    x = r.get_poses()
    if np.size(at_position(x[:2], goals, position_error=0.05)) == N:
        break
    r.set_velocities(np.arange(N), barrier(controller(x, goals), x))
    for i in range(N):
        markers[i].set_sizes([determine_marker_size(r, 0.1)])
    r.step()
r.call_at_scripts_end()
