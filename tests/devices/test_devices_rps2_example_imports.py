"""rps's examples import their own helpers through the rps package (the EKF example:
``from rps.examples.state_estimation.extended_kalman_filter.uni_ekf import UnicycleEKF``): under swarmdeck
``rps.examples.….NAME`` is the file NAME.py beside the script, the folders the script is in are its packages, and
nothing else of ``rps.examples`` exists."""
from __future__ import annotations

from swarmdeck.devices.runner import run_experiment

SCRIPT = """
import numpy as np
import rps.robotarium as robotarium
from rps.examples.state_estimation.extended_kalman_filter.helper import GAIN

r = robotarium.Robotarium(number_of_robots=1, show_figure=False)
x = r.get_poses()
r.set_velocities(np.arange(1), np.array([[GAIN], [0.0]]))
r.step()
for missing in ("rps.examples.state_estimation.nothing", "rps.examples.elsewhere.helper"):
    try:
        __import__(missing)
    except ImportError as exc:
        print("MISSING", type(exc).__name__)
r.debug()
"""


def test_rps_examples_imports_resolve_to_the_scripts_folder(tmp_path, capsys):
    folder = tmp_path / "state_estimation" / "extended_kalman_filter"
    folder.mkdir(parents=True)
    (folder / "helper.py").write_text("GAIN = 0.1\n")
    (folder / "main.py").write_text(SCRIPT)
    result = run_experiment(folder / "main.py")
    assert result.ok, result.error
    assert capsys.readouterr().out.count("MISSING ModuleNotFoundError") == 2
    assert result.reports[0].time > 0
