"""An rps 2.x script's ``obstacles`` are solid for swarmdeck's barrier, in process and in the sandbox: a script that
drives its robots straight into its own obstacle is stopped in front of it (no obstacle contact), and the lab's
``[arena] obstacles`` given to an rps script are solid and seen by its distance sensors too. Sandboxed, the script's
readings are the trusted side's and the LEDs it sets are shown there."""
from __future__ import annotations

import textwrap

import numpy as np
import pytest

from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.core.obstacles import ObstacleError, Obstacles
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.runner import run_experiment
from swarmdeck.devices.simulator import ArenaConfig

# two robots heading east (+x) at 0.15 m/s for 100 steps (3.3 s): 0.5 m of travel, the obstacle 0.35 m ahead of them
SCRIPT = """
import numpy as np
import rps.robotarium as robotarium

obstacles = np.array([[[0.0, -0.6], [0.0, 0.6]]])  # a wall across the robots' way (M x 2 x 2, m)
ic = np.array([[-0.35, -0.35], [-0.3, 0.3], [0.0, 0.0]])
r = robotarium.Robotarium(number_of_robots=2, show_figure=False, initial_conditions=ic, sim_in_real_time=False,
                          obstacles=obstacles, use_distance_sensors=True)
r.set_leds(np.arange(2), np.array([[255, 0], [0, 128], [0, 0]]))  # (3, N): red, then green
for _ in range(100):
    r.get_poses()
    r.set_velocities(np.arange(2), np.array([[0.15, 0.15], [0.0, 0.0]]))
    r.step()
d = r.get_distances()
seen = d[:, 0][d[:, 0] >= 0]  # robot 0's seven sensors: -1 is nothing in range
print("front", float(seen.min()) if seen.size else "nothing")
r.debug()
"""


def _script(tmp_path, body=SCRIPT):
    path = tmp_path / "into_the_wall.py"
    path.write_text(textwrap.dedent(body))
    return path


def test_an_rps2_scripts_obstacle_stops_its_robots_in_process(tmp_path):
    result = run_experiment(_script(tmp_path), rps=True, rps_generation=2)
    assert result.ok, result.error
    arena = result.arenas[0]
    report = arena.report().validation
    assert report.steps_with_obstacle_contact == 0
    assert np.all(arena.poses()[:, 0] < -0.05)  # stopped in front of the wall, not pressed against it
    assert arena.config.obstacles is not None and arena.config.obstacles.m == 1
    assert 0.0 < _front(result.returned, arena) < 0.3


def _front(_, arena):
    d = arena.sense().distances[0]
    return float(d[d >= 0].min())


def test_the_labs_obstacles_join_the_scripts_for_an_rps_script(tmp_path):
    lab = Obstacles([[[1.0, -0.5], [1.0, 0.5]]])
    result = run_experiment(_script(tmp_path), rps=True, rps_generation=2, obstacles=lab)
    assert result.ok, result.error
    arena = result.arenas[0]
    assert arena.config.obstacles.m == 2  # the lab's and the script's, both solid and both sensed
    assert arena.sensors is not None and arena.sensors.obstacles.shape == (2, 2, 2)
    assert arena.report().validation.steps_with_obstacle_contact == 0


def test_an_obstacle_added_across_a_robot_is_refused_naming_it():
    arena = Arena(1, initial_conditions=[[0.0, 0.0, 0.0]], config=ArenaConfig(seed=1))
    with pytest.raises(ObstacleError, match="segment 0"):
        arena.add_obstacles([[[0.05, -0.2], [0.05, 0.2]]])
    assert arena.config.obstacles is None  # nothing changed


@pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
def test_an_rps2_scripts_obstacle_stops_its_robots_in_the_sandbox(tmp_path):
    arenas: list[Arena] = []

    def make_plant(n, initial):
        arenas.append(Arena(n, initial_conditions=initial, config=ArenaConfig(seed=3), duration=5.0))
        return ArenaPlant(arenas[-1])

    out = run_sandboxed(_script(tmp_path), make_plant, n_robots=2, duration=5.0, rps=True, rps_generation=2,
                        robot_model="gternal")
    assert out.ok, out.error
    arena = arenas[0]
    assert arena.config.obstacles is not None and arena.config.obstacles.m == 1  # sent across, made solid
    assert arena.report().validation.steps_with_obstacle_contact == 0
    assert np.all(arena.poses()[:, 0] < -0.05)
    front = next(line for line in out.log.splitlines() if line.startswith("front")).split()[1]
    assert 0.0 < float(front) < 0.3, out.log  # its sensors saw the wall ahead
    assert float(front) == pytest.approx(_front(None, arena))  # the trusted side's readings, sent to the script
    assert arena.sensors.leds.tolist() == [[255, 0, 0], [0, 128, 0]]  # the LEDs it set, shown on the trusted side


# four robots at random start poses among five walls across the arena: random starts must know the script's walls
WALLS = """
import numpy as np
import rps.robotarium as robotarium

walls = np.array([[[-1.5, y], [1.5, y]] for y in (-0.8, -0.4, 0.0, 0.4, 0.8)])
r = robotarium.Robotarium(number_of_robots=4, show_figure=False, sim_in_real_time=False, obstacles=walls)
for _ in range(5):
    r.get_poses()
    r.step()
print("walls", r.obstacles.shape[0])
r.debug()
"""


@pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
def test_random_start_poses_of_a_sandboxed_run_keep_clear_of_the_scripts_obstacles(tmp_path, capsys):
    from swarmdeck.console.cli import main

    script = tmp_path / "walls.py"
    script.write_text(textwrap.dedent(WALLS))
    assert main(["run", "--sandbox", str(script), "--duration", "0.3", "--seed", "2", "--rps-generation", "2"]) == 0
    assert "walls 5" in capsys.readouterr().out
