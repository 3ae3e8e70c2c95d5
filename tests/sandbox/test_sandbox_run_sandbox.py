"""`swarmdeck run --sandbox`: both API styles run in the jailed child and move the robots as an in-process run does."""
import json
import textwrap

import numpy as np
import pytest

from swarmdeck.console.cli import main
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.runner import run_experiment
from swarmdeck.devices.simulator import ArenaConfig

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

STYLES = {
    "experiment": """
        def experiment(arena):
            while True:
                p = arena.positions()
                arena.set_velocities(-(p - p.mean(axis=0)))
                arena.step()
    """,
    "rps": """
        import numpy as np
        import rps.robotarium as robotarium
        from rps.utilities.transformations import create_si_to_uni_dynamics
        r = robotarium.Robotarium(number_of_robots=4, show_figure=False)
        si_to_uni = create_si_to_uni_dynamics()
        for _ in range(40):
            x = r.get_poses()
            r.set_velocities(np.arange(4), si_to_uni(-(x[:2] - x[:2].mean(axis=1, keepdims=True)), x))
            r.step()
        r.call_at_scripts_end()
        print("rps script done")
    """,
}


@pytest.mark.parametrize("style", sorted(STYLES))
def test_sandboxed_and_in_process_runs_agree(tmp_path, style):
    script = tmp_path / f"{style}.py"
    script.write_text(textwrap.dedent(STYLES[style]))
    direct = run_experiment(script, n_robots=4, duration=1.0, seed=5)
    assert direct.ok, direct.error
    config = ArenaConfig(seed=5)
    out = run_sandboxed(script, lambda n, ic: ArenaPlant(Arena(n, initial_conditions=ic, config=config, duration=1.0)),
                        n_robots=4, duration=1.0)
    assert out.ok, out.error
    arena = out.plant.arena
    assert arena.safety is not None and arena.safety_stats.calls == out.ticks > 0  # the trusted side filtered every tick
    assert out.ticks == direct.reports[0].validation.steps
    # the script's nominal crosses the pipe as it is and is certified once, on the trusted side: bit for bit
    np.testing.assert_array_equal(arena.poses(), direct.arenas[0].poses())


def test_cli_run_sandbox_prints_the_trusted_report_and_the_scripts_output(tmp_path, capsys):
    script = tmp_path / "rps_style.py"
    script.write_text(textwrap.dedent(STYLES["rps"]))
    assert main(["run", "--sandbox", str(script), "--seed", "1", "--json"]) == 0
    out = capsys.readouterr().out
    report = json.loads(out[out.index("{\n"):])
    assert report["ended_by"] == "script" and report["reports"][0]["validation"]["steps"] == 40
    assert "rps script done" in out  # the script's output
    assert "safety filter: OFF" not in out  # the report is the trusted side's, once: the child's call_at_scripts_end
    # (the child has no filter, swarmdeck does) prints nothing under the runner (before: a second, wrong report)
    assert report["reports"][0]["safety"]["enabled"] is True


def test_cli_run_sandbox_error_is_one_line_exit_2(tmp_path, capsys):
    script = tmp_path / "bad.py"
    script.write_text("def experiment(arena):\n    arena.step()\n    1 / 0\n")
    assert main(["run", "--sandbox", str(script), "--robots", "2", "--duration", "1"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "bad.py:3 (in experiment): ZeroDivisionError" in err
