"""Arena(from_docks=True), the rps facade and `swarmdeck run --from-docks`: set up, run, return, report."""
import json

import numpy as np
import pytest

from swarmdeck.console.cli import main
from swarmdeck.core.kinematics import wrap_angle
from swarmdeck.devices import Arena, ArenaConfig, ExperimentFinished
from swarmdeck.devices.rps.robotarium import Robotarium

SCRIPT = """\
import numpy as np
from swarmdeck.devices import Arena
arena = Arena(6, duration=3.0)
while True:
    p = arena.positions()
    arena.set_velocities(0.5 * (p.mean(axis=0) - p))
    arena.step()
"""


def test_an_arena_from_the_docks_starts_at_its_initial_conditions_and_returns():
    start = np.array([[-0.5, 0.0, 0.0], [0.5, 0.0, np.pi], [0.0, 0.5, -np.pi / 2], [0.0, -0.5, np.pi / 2]])
    arena = Arena(initial_conditions=start, from_docks=True, config=ArenaConfig(seed=2), duration=1.0)
    p = arena.poses()
    assert arena.time == 0.0 and arena.fleet.last_setup.ok
    assert np.all(np.hypot(*(p[:, :2] - start[:, :2]).T) <= 0.02)
    assert np.all(np.abs(wrap_angle(p[:, 2] - start[:, 2])) <= np.deg2rad(5))
    with pytest.raises(ExperimentFinished):
        while True:
            arena.set_velocities(-arena.positions() * 0.5)
            arena.step()
    arena.return_to_chargers()
    fleet = arena.report().to_dict()["fleet"]
    assert fleet["return"]["ok"] and fleet["ready"] and fleet["collisions"] == 0
    assert arena.fleet.docked().all() and abs(arena.time - 1.0) < 0.05


def test_start_poses_too_close_are_named_before_anything_moves():
    with pytest.raises(ValueError, match="start poses 0 and 1 are 0.100 m apart"):
        Arena(initial_conditions=np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]]), from_docks=True)


def test_the_rps_facade_sets_robots_up_to_its_initial_conditions():
    ic = np.array([[-0.4, 0.4, 0.0], [0.0, 0.0, 0.3], [0.0, 0.0, 1.0]])  # (3, N)
    r = Robotarium(number_of_robots=3, show_figure=False, sim_in_real_time=False, initial_conditions=ic,
                   from_docks=True)
    x = r.get_poses()
    assert np.all(np.hypot(*(x[:2] - ic[:2])) <= 0.02)
    assert r.arena.fleet.last_setup.collision_steps == 0


def test_swarmdeck_run_from_docks_reports_setup_return_error_and_collisions(tmp_path, capsys):
    script = tmp_path / "gather.py"
    script.write_text(SCRIPT)
    assert main(["run", str(script), "--from-docks", "--seed", "3", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)["reports"][0]
    fleet = report["fleet"]
    assert fleet["setup"]["ok"] and fleet["setup"]["sim_time"] > 0 and fleet["setup"]["wall_time"] > 0
    assert fleet["setup"]["max_position_error"] <= 0.02 and fleet["setup"]["max_heading_error_deg"] <= 5
    assert fleet["return"]["ok"] and fleet["return"]["sim_time"] > 0 and fleet["collisions"] == 0 and fleet["ready"]
    assert main(["run", str(script), "--from-docks", "--seed", "3"]) == 0
    text = capsys.readouterr().out
    assert "fleet: set up from the chargers in" in text and "returned to the chargers in" in text
    assert "collisions 0 steps; ready" in text


def test_from_docks_with_sandbox_is_a_usage_error(tmp_path, capsys):
    script = tmp_path / "s.py"
    script.write_text(SCRIPT)
    assert main(["run", str(script), "--from-docks", "--sandbox"]) == 2
    assert "--from-docks does not combine with --sandbox" in capsys.readouterr().err
