"""The Robotarium 2.0 examples that need rps 2.x's sensors (distances, encoders, IMU) or obstacles run unchanged under
``swarmdeck run`` and end as under rps 2.0: every robot reaches its goals (the script's own loop ends), no collision,
no robot outside the arena, and ``debug()`` says the script will run on the Robotarium (issue 28 items 1, 3, 4).

They need the sensing layer (issue 28.1) behind the rps facade; a script's ``obstacles`` are segments the sensors see,
as in rps 2.0 (distance_sensor_avoidance.py). The examples that need neither are in test_devices_rps2_examples.py.
"""
from __future__ import annotations

import pytest
from rps2_examples import DEBUG_ACCEPTED, DEBUG_HEAD, run_example

from swarmdeck.core.constants import GTERNAL_BASE_LENGTH

GOALS = 120.0  # s: a cap the examples never reach under rps 2.0
SENSORS, OBSTACLES, PLOT = pytest.mark.rps2_sensors, pytest.mark.rps2_obstacles, pytest.mark.rps2_plotting

#: (example, its own command-line arguments, marks): the EKF example drives its rectangle once (its ``--cycles``
#: option; the default is twice, and its per-step cost grows with the run as it redraws its whole history)
CASES = [
    ("master/sensors/sensor_readings.py", (), (SENSORS,)),
    ("master/sensors/distance_sensor_avoidance.py", (), (SENSORS, OBSTACLES)),
    ("master/state_estimation/dead_reckoning/dead_reckoning.py", (), (SENSORS,)),
    ("master/plotting/dead_reckoning_with_plotting.py", (), (SENSORS, PLOT)),
    ("master/state_estimation/extended_kalman_filter/ekf_experiment.py", ("--cycles", "1"), (SENSORS, PLOT)),
]


@pytest.mark.parametrize("name, argv", [pytest.param(n, a, marks=m, id=n) for n, a, m in CASES])
def test_sensor_example_runs_unchanged_and_reaches_its_goals(name, argv, tmp_path):
    run = run_example(name, tmp_path, duration=GOALS, argv=argv)
    assert run.result.ok, run.result.error
    report = run.report
    assert report.validation.steps_with_collision == 0 and report.validation.steps_with_boundary == 0, str(report)
    assert run.arenas[0].params.axle_length == GTERNAL_BASE_LENGTH
    assert report.time < GOALS - 1.0, "the script's own loop ended: every robot reached its goal"
    assert DEBUG_HEAD in run.output and any(verdict in run.output for verdict in DEBUG_ACCEPTED), run.output
