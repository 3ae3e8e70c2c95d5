"""rps semantics (`Robotarium(..., rps_semantics=True)`, `swarmdeck run --rps-semantics`): no barrier but the
script's own, and rps's error counts in `_errors`, `debug()` and `call_at_scripts_end()` exactly as rps's."""
import textwrap

import numpy as np

from swarmdeck.console.cli import main
from swarmdeck.devices.rps.robotarium import Robotarium


def rps1_validate(errors, p, velocities, boundaries, wheel_radius, base_length, max_wheel):
    """rps 1.x's RobotariumABC._validate (`dev` branch), loops and all: the oracle."""
    b = boundaries
    n = p.shape[1]
    for i in range(n):
        x, y = p[0, i], p[1, i]
        if x < b[0] or x > (b[0] + b[2]) or y < b[1] or y > (b[1] + b[3]):
            errors.setdefault("boundary", {})
            errors["boundary"][i] = errors["boundary"].get(i, 0) + 1
            errors["boundary_string"] = "iteration(s) robots were outside the boundaries."
    for j in range(n - 1):
        for k in range(j + 1, n):
            first = p[:2, j] + 0.025 * np.array([np.cos(p[2, j]), np.sin(p[2, j])])
            second = p[:2, k] + 0.025 * np.array([np.cos(p[2, k]), np.sin(p[2, k])])
            if np.linalg.norm(first - second) <= 0.135:
                errors.setdefault("collision", {})
                errors["collision"][j] = errors["collision"].get(j, 0) + 1
                errors["collision"][k] = errors["collision"].get(k, 0) + 1
                errors["collision_string"] = "iteration(s) where robots collided."
    r, base = wheel_radius, base_length
    dxdd = np.vstack((1 / (2 * r) * (2 * velocities[0] - base * velocities[1]),
                      1 / (2 * r) * (2 * velocities[0] + base * velocities[1])))
    if np.any(np.abs(dxdd) > max_wheel):
        errors["actuator"] = errors.get("actuator", 0) + 1
        errors["actuator_string"] = ("iteration(s) where the actuator limits of at least one robot were exceeded and "
                                     "thresholded to their maximum rotational velocity.")
    # rps 2.0 (`master`): steps out of bounds, colliding pairs, steps over the actuator limits
    if _any_out(p, b):
        errors["robots_outside_boundaries"] = errors.get("robots_outside_boundaries", 0) + 1
    return errors


def _any_out(p, b):
    return bool(np.any((p[0] < b[0]) | (p[0] > b[0] + b[2]) | (p[1] < b[1]) | (p[1] > b[1] + b[3])))


def test_errors_are_counted_as_rps_counts_them():
    rng = np.random.default_rng(4)
    ic = np.array([[-0.3, 0.3, 0.0, 1.45, -1.0], [0.0, 0.0, 0.5, 0.0, -0.8], [0.0, np.pi, 0.0, 0.0, -np.pi / 2]])
    r = Robotarium(5, initial_conditions=ic, sim_in_real_time=False, rps_semantics=True)
    assert r.arena.safety is None  # no barrier but the script's own
    oracle: dict = {}
    pairs = steps_over = 0
    for _ in range(150):
        x = r.get_poses()
        vel = np.vstack((np.full(5, 0.15), rng.normal(0, 2.0, 5)))
        vel[:, 3] = [0.1, 0.0]  # robot 3 drives out through the right wall
        vel[0, 4] = 0.4 if _ < 10 else 0.05  # robot 4 over its wheel limits for a while
        r.set_velocities(np.arange(5), vel)
        prev = {k: v for k, v in oracle.items()}
        rps1_validate(oracle, x, vel, r.boundaries, r.wheel_radius, r.base_length, r.max_wheel_velocity)
        shifted = x[:2] + 0.025 * np.vstack((np.cos(x[2]), np.sin(x[2])))
        d = np.linalg.norm(shifted[:, :, None] - shifted[:, None, :], axis=0)
        pairs += int(np.triu(d <= 0.135, 1).sum())
        steps_over += "actuator" in oracle and oracle.get("actuator") != prev.get("actuator")
        r.step()
    e = r._errors
    for key in ("boundary", "collision", "actuator", "boundary_string", "collision_string", "actuator_string"):
        assert e.get(key) == oracle.get(key), key  # rps 1.x, key for key
    assert e["collision"] and e["boundary"][3] > 0 and e["actuator"] >= 10  # the run did collide, leave, saturate
    assert e["robots_too_close"] == pairs and e["exceeded_actuator_limits"] == steps_over  # rps 2.0
    assert e["robots_outside_boundaries"] == oracle["robots_outside_boundaries"]


def test_debug_and_call_at_scripts_end_print_rps_texts(capsys):
    ic = np.array([[-0.05, 0.05], [0.0, 0.0], [0.0, np.pi]])
    r = Robotarium(2, initial_conditions=ic, sim_in_real_time=False, rps_semantics=True)
    for _ in range(3):
        r.get_poses()
        r.step()
    r.debug()
    r.call_at_scripts_end()
    out = capsys.readouterr().out
    assert ("Your simulation took approximately 0.10 real seconds to execute.\n\n"
            "Errors detected, your script will NOT run on the Robotarium!\n\nErrors:\n"
            "\t Simulation had 3 time steps where robots were too close (potential collision).\n"
            "\nPlease fix the noted errors in your simulation; otherwise, your experiment will be rejected.\n") in out
    assert ("##### DEBUG OUTPUT #####\n"
            "Your simulation will take approximately 1 real seconds when deployed on the Robotarium. \n\n"
            "\t Simulation had 3 iteration(s) where robots collided.\n") in out
    clean = Robotarium(2, sim_in_real_time=False, rps_semantics=True)
    clean.get_poses()
    clean.step()
    clean.debug()
    assert "No errors or warnings in your simulation!  Your script will run on the Robotarium!" in capsys.readouterr().out


def test_cli_rps_semantics_applies_only_the_scripts_barrier(tmp_path, capsys):
    script = tmp_path / "head_on.py"
    script.write_text(textwrap.dedent("""
        import numpy as np
        import rps.robotarium as robotarium
        r = robotarium.Robotarium(number_of_robots=2, show_figure=False,
                                  initial_conditions=np.array([[-0.4, 0.4], [0.0, 0.0], [0.0, np.pi]]))
        for _ in range(120):
            r.get_poses()
            r.set_velocities(np.arange(2), np.array([[0.15, 0.15], [0.0, 0.0]]))
            r.step()
        print("too close:", r._errors.get("robots_too_close", 0))
    """))
    assert main(["run", str(script), "--rps-semantics"]) == 0
    out = capsys.readouterr().out
    assert "safety filter: OFF" in out and "too close: 0" not in out  # rps: nothing stops the head-on run
    assert main(["run", str(script)]) == 0
    out = capsys.readouterr().out
    assert "too close: 0" in out and "safety filter: 120 calls" in out  # default: the arena's barrier
