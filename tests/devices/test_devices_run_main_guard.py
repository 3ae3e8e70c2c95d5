"""`swarmdeck run` runs a script as `python script.py` would: as `__main__`, with its own arguments."""
import textwrap

import pytest

from swarmdeck.console.cli import main
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.runner import ScriptError, run_experiment

GUARDED = """
    import sys
    import numpy as np
    import rps.robotarium as robotarium

    def run(steps):
        r = robotarium.Robotarium(number_of_robots=3, show_figure=False)
        for _ in range(steps):
            r.get_poses()
            r.set_velocities(np.arange(3), np.zeros((2, 3)))
            r.step()
        print("ran", steps, "steps as", __name__)

    if __name__ == "__main__":
        run(int(sys.argv[1]) if len(sys.argv) > 1 else 5)
"""


def test_code_under_the_main_guard_runs_with_the_scripts_arguments(tmp_path, capsys):
    script = tmp_path / "guarded.py"
    script.write_text(textwrap.dedent(GUARDED))
    result = run_experiment(script, argv=["7"])
    assert result.ok, result.error
    assert result.reports[0].validation.steps == 7
    assert "ran 7 steps as __main__" in capsys.readouterr().out
    assert main(["run", str(script), "--", "4"]) == 0
    assert "ran 4 steps as __main__" in capsys.readouterr().out


def test_a_guard_that_builds_nothing_is_named_in_the_error(tmp_path, capsys):
    script = tmp_path / "nothing.py"
    script.write_text('import sys\n\nif __name__ == "__main__":\n    if len(sys.argv) > 1:\n        print("go")\n')
    with pytest.raises(ScriptError) as exc:
        run_experiment(script)
    text = str(exc.value)
    assert "experiment(arena)" in text and "Arena" in text and "Robotarium" in text  # what was looked for
    assert '__name__ == "__main__"' in text  # and that the guard exists (and ran)
    assert main(["run", str(script)]) == 2
    assert "__main__" in capsys.readouterr().err


@pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
def test_the_sandboxed_child_runs_the_script_as_main_too(tmp_path):
    script = tmp_path / "guarded.py"
    script.write_text(textwrap.dedent(GUARDED))
    out = run_sandboxed(script, lambda n, ic: ArenaPlant(Arena(n, initial_conditions=ic, duration=1.0)), duration=1.0)
    assert out.ok, out.error_line
    assert out.ticks == 5 and "ran 5 steps as __main__" in out.log
