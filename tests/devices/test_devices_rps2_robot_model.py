"""The robot model is a choice: the GRITSBot (default) or Robotarium 2.x's GTernal (REFERENCE.md §15), in the arena
config (``[arena] robot_model``), ``swarmdeck run --robot-model`` and code; an rps 2.x script gets the GTernal's
constants and dynamics, a 1.x script the GRITSBot's (issue 28 item 4)."""
from __future__ import annotations

import subprocess

import numpy as np
import pytest
from marbler_fixtures import swarmdeck_cli

from swarmdeck.console.runtime.config import ConfigFileError, load_settings
from swarmdeck.core.constants import AXLE_LENGTH, CONTROL_PERIOD
from swarmdeck.core.robot_models import ROBOT_MODELS, robot_params
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.rps import rps_aliases
from swarmdeck.devices.rps.generation import script_generation
from swarmdeck.devices.runner import run_experiment

SCRIPT = """
import numpy as np
import rps.robotarium as robotarium
r = robotarium.Robotarium(number_of_robots=1, show_figure=False, initial_conditions=np.array([[0.0], [0.0], [0.0]]){extra})
x = r.get_poses()
r.set_velocities(np.arange(1), np.array([[0.0], [10.0]]))  # spin in place, far beyond the wheel limits
r.step()
x = r.get_poses()
turned = float(x[2, 0])
constants = (r.BASE_LENGTH, r.ROBOT_DIAMETER, r.WHEEL_RADIUS, r.MAX_LINEAR_VELOCITY, r.MAX_WHEEL_VELOCITY,
             r.MAX_ANGULAR_VELOCITY, r.COLLISION_DIAMETER, r.COLLISION_OFFSET, r.robot_model)
r.{end}()
"""


def _run(tmp_path, end: str, extra: str = "", **kw):
    path = tmp_path / "script.py"
    path.write_text(SCRIPT.format(end=end, extra=extra))
    seen = {}
    result = run_experiment(path, on_create=lambda arena: seen.setdefault("arena", arena), **kw)
    assert result.ok, result.error
    return seen["arena"]


def test_the_gternal_has_robotarium_2x_constants():
    g, grits = robot_params("gternal"), robot_params("GRITSBot")
    assert (g.diameter, g.wheel_radius, g.axle_length, g.max_speed, g.max_wheel_speed) == (0.11, 0.016, 0.11, 0.2, 12.5)
    assert g.max_angular_speed == pytest.approx(2 * 0.2 / 0.11)  # rps 2.x: 2 (r / D) (v_max / r)
    assert grits.axle_length == AXLE_LENGTH and grits == ROBOT_MODELS["gritsbot"]
    for bad in ("tank", "", None, 3):
        with pytest.raises(ValueError, match=r"robot_model .* choose one of \['gritsbot', 'gternal'\]"):
            robot_params(bad)


def test_an_rps_script_gets_the_robot_of_its_generation_in_constants_and_in_motion(tmp_path):
    two = _run(tmp_path, "debug")  # a 2.x script ends with r.debug()
    one = _run(tmp_path, "call_at_scripts_end")  # a 1.x script with r.call_at_scripts_end()
    assert two.params == robot_params("gternal") and one.params == robot_params("gritsbot")
    # the spin was limited by each model's own wheels: ω_max = 2 r ω_wheel / L for one step of 0.033 s
    for arena in (two, one):
        assert arena.poses()[0, 2] == pytest.approx(arena.params.max_angular_speed * CONTROL_PERIOD, rel=1e-6)
    assert two.poses()[0, 2] < one.poses()[0, 2]  # the GTernal's longer base turns more slowly


def test_the_choice_overrides_the_generation(tmp_path):
    assert _run(tmp_path, "debug", robot_model="gritsbot").params == robot_params("gritsbot")
    assert _run(tmp_path, "call_at_scripts_end", robot_model="gternal").params == robot_params("gternal")
    assert _run(tmp_path, "debug", rps_generation=1).params == robot_params("gritsbot")
    assert _run(tmp_path, "call_at_scripts_end", extra=", robot_model='gternal'").params == robot_params("gternal")
    with pytest.raises(ValueError, match="robot_model 'tank'"):
        run_experiment(tmp_path / "script.py", robot_model="tank")
    with pytest.raises(ValueError, match="rps_generation must be 1 or 2"):
        run_experiment(tmp_path / "script.py", rps_generation=3)


def test_the_facade_reports_the_constants_of_its_model(tmp_path):
    with rps_aliases():
        import rps.robotarium as robotarium
        from rps.robotarium_abc import ARobotarium

        g = robotarium.Robotarium(number_of_robots=2, robot_model="gternal")
        r = robotarium.Robotarium(number_of_robots=2)  # outside a run: the arena's default robot
    assert isinstance(g, ARobotarium)
    assert ARobotarium.BASE_LENGTH == 0.11 and ARobotarium.MAX_ANGULAR_VELOCITY == pytest.approx(0.4 / 0.11)
    assert list(ARobotarium.BOUNDARIES) == [-1.6, 1.6, -1.0, 1.0] and ARobotarium.TIME_STEP == CONTROL_PERIOD
    assert (g.BASE_LENGTH, g.base_length, g.robot_model) == (0.11, 0.11, "gternal")
    assert (r.BASE_LENGTH, r.robot_model) == (AXLE_LENGTH, "gritsbot")
    assert (g.COLLISION_DIAMETER, g.COLLISION_OFFSET) == (0.135, 0.025)
    with rps_aliases():
        import rps.robotarium as robotarium

        with pytest.raises(ValueError, match="robot_model 'tank'"):
            robotarium.Robotarium(number_of_robots=2, robot_model="tank")


def test_generation_is_read_from_how_the_script_ends():
    assert script_generation("r.debug()\n") == 2
    assert script_generation("r.call_at_scripts_end()\n") == 1
    assert script_generation("r.debug()\nr.call_at_scripts_end()") == 1  # 2.x has no call_at_scripts_end
    assert script_generation("x = 1") is None
    assert script_generation("logger.debug('x')") is None  # debug with arguments is not rps's


def test_arena_config_chooses_the_console_robot(tmp_path):
    path = tmp_path / "arena.toml"
    path.write_text('[arena]\nrobot_model = "gternal"\n')
    assert load_settings(path).robot_model == "gternal"
    path.write_text("[console]\nrobots = 3\n")
    assert load_settings(path).robot_model == "gritsbot"  # the GRITSBot stays the console's default
    path.write_text('[arena]\nrobot_model = "tank"\n')
    with pytest.raises(ConfigFileError, match=r"\[arena\] robot_model 'tank'.*gternal"):
        load_settings(path)
    path.write_text('[arena]\nrobot = "gternal"\n')
    with pytest.raises(ConfigFileError, match=r"unknown key.*robot.*\[arena\]"):
        load_settings(path)


def test_arena_runs_the_model_it_is_given():
    arena = Arena(1, initial_conditions=np.zeros((1, 3)), params=robot_params("gternal"), safety=False)
    arena.step_unicycle(np.zeros(1), np.full(1, 10.0))
    assert arena.poses()[0, 2] == pytest.approx(0.4 / 0.11 * CONTROL_PERIOD, rel=1e-6)


def test_swarmdeck_run_takes_robot_model_and_refuses_an_unknown_one(tmp_path):
    path = tmp_path / "script.py"
    path.write_text(SCRIPT.format(end="debug", extra="") + "print('MODEL', constants[-1], constants[0])\n")
    done = subprocess.run([*swarmdeck_cli(), "run", str(path), "--robot-model", "gritsbot"], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert "MODEL gritsbot 0.105" in done.stdout
    done = subprocess.run([*swarmdeck_cli(), "run", str(path), "--robot-model", "tank"], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 2 and "--robot-model: invalid choice: 'tank'" in done.stderr
