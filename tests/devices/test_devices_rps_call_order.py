"""The rps facade enforces rps's call order (get_poses() once per step(), no step() twice), as the
Robotarium does, with rps's AssertionError; a documented switch relaxes it."""
import textwrap

import numpy as np
import pytest

from swarmdeck.console.cli import main
from swarmdeck.devices.rps.robotarium import Robotarium
from swarmdeck.devices.runner import run_experiment

# rps's messages: 2.0 (`master`) words them so; 1.x (`dev`) "… once per call of step()." / "Make sure to call …"
GET_TWICE = "Can only call get_poses() once per call of step()"
STEP_TWICE = "call get_poses before calling step()"


def test_get_poses_twice_per_step_raises_rps_assertion():
    r = Robotarium(number_of_robots=2, sim_in_real_time=False)
    r.get_poses()
    with pytest.raises(AssertionError, match=GET_TWICE.replace("(", r"\(").replace(")", r"\)")):
        r.get_poses()


def test_step_without_get_poses_raises_rps_assertion():
    r = Robotarium(number_of_robots=2, sim_in_real_time=False)
    with pytest.raises(AssertionError, match=r"call get_poses before calling step\(\)"):
        r.step()  # as in rps: the first call must be get_poses()
    r.get_poses()
    r.step()
    with pytest.raises(AssertionError, match=r"call get_poses before calling step\(\)"):
        r.step()


def test_the_right_order_runs_and_the_switch_relaxes_it(tmp_path, capsys):
    r = Robotarium(number_of_robots=2, sim_in_real_time=False)
    for _ in range(3):
        r.get_poses()
        r.set_velocities(np.arange(2), np.zeros((2, 2)))
        r.step()
    relaxed = Robotarium(number_of_robots=2, sim_in_real_time=False, enforce_call_order=False)
    relaxed.get_poses()
    relaxed.get_poses()
    relaxed.step()
    relaxed.step()
    script = tmp_path / "twice.py"
    script.write_text(textwrap.dedent("""
        import numpy as np
        import rps.robotarium as robotarium
        r = robotarium.Robotarium(number_of_robots=2, show_figure=False)
        for _ in range(3):
            x = r.get_poses()
            x = r.get_poses()
            r.step()
    """))
    result = run_experiment(script)
    assert not result.ok and GET_TWICE in result.error_line
    assert main(["run", str(script)]) == 2
    assert GET_TWICE in capsys.readouterr().err
    assert run_experiment(script, rps_call_order=False).ok
    assert main(["run", str(script), "--no-rps-call-order"]) == 0
