"""Sensors inside the sandbox's jail (issue 28.1): an experiment and an rps 2.x script that read the ToF sensors run
confined. The jail's code folders are read-only, so numba cannot save the ray-cast kernels it compiles there; the
kernels still run (failed before: OSError, Read-only file system). The experiment runs more robots than
``core.graphs.DENSE_PAIRS_ROBOTS``, so its casts take the compiled kernels (fewer robots take numpy)."""
from pathlib import Path

import numpy as np
import pytest

from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.core.graphs import DENSE_PAIRS_ROBOTS
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.simulator import ArenaConfig

confined = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "sensor_avoidance.py"

RPS2 = """
import numpy as np
import rps.robotarium as robotarium

r = robotarium.Robotarium(number_of_robots=2, show_figure=False, sim_in_real_time=False, use_distance_sensors=True,
                          obstacles=np.array([[[0.5, -0.8], [0.5, 0.8]]]))
for _ in range(10):
    x = r.get_poses()
    r.set_velocities(np.arange(2), np.array([[0.1, 0.1], [0.0, 0.0]]))
    r.step()
d = r.get_distances()
print("SHAPE", d.shape, r.get_encoders().shape, r.get_distance_endpoints().shape)
"""


def plant(n, initial):
    return ArenaPlant(Arena(n, initial_conditions=initial, config=ArenaConfig(seed=2), duration=1.0))


@confined
def test_an_experiment_reading_its_sensors_runs_in_the_jail():
    out = run_sandboxed(EXAMPLE, plant, n_robots=DENSE_PAIRS_ROBOTS + 1, duration=1.0)  # the compiled casts
    assert out.ok, out.error
    assert out.ticks > 0


@confined
def test_an_rps_2x_sensor_script_runs_in_the_jail(tmp_path):
    script = tmp_path / "sensors_2x.py"
    script.write_text(RPS2)
    out = run_sandboxed(script, plant, n_robots=2, rps=True)
    assert out.ok, out.error
    assert "SHAPE (7, 2) (2, 2) (2, 7, 2)" in out.log
    assert np.isfinite(out.ticks)
