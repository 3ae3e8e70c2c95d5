"""`swarmdeck run` / `swarmdeck example`: every user mistake is one clear line and exit 2, never a traceback."""
import textwrap

import pytest

from swarmdeck.console.cli import main

SCRIPTS = {
    "raises": ("def experiment(arena):\n    arena.step()\n    raise RuntimeError('boom')\n", "raises.py:3 (in experiment): RuntimeError: boom"),
    "shape": ("import numpy as np\ndef experiment(arena):\n    arena.set_velocities(np.zeros((1, 3)))\n",
              "shape.py:3 (in experiment): ValueError: velocities must have shape (2, 2)"),
    "intposes": ("import numpy as np\nfrom swarmdeck.devices import Arena\nArena(initial_conditions=np.array([[0, 0, 0]]))\n",
                 "intposes.py:3 (in <module>): ValueError: initial_conditions must be a float array"),
    "exits": ("import sys\ndef experiment(arena):\n    sys.exit(3)\n", "called sys.exit(3)"),
    "syntax": ("def experiment(arena)\n    pass\n", "syntax error in"),
}


@pytest.mark.parametrize("name", sorted(SCRIPTS))
def test_bad_scripts_give_one_line_and_exit_2(name, tmp_path, capsys):
    source, expected = SCRIPTS[name]
    script = tmp_path / f"{name}.py"
    script.write_text(source)
    assert main(["run", str(script), "--robots", "2", "--duration", "1", "--seed", "0"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert len(err.strip().splitlines()) == 1 and expected in err


@pytest.mark.parametrize("argv", [
    ["run", "{script}", "--robots", "500"],
    ["run", "{script}", "--duration", "inf"],
    ["run", "{script}", "--duration", "nan"],
    ["example", "rendezvous", "--robots", "500"],
    ["example", "formation", "--duration", "inf"],
    ["example", "formation", "--robots", "2"],
    ["example", "rendezvous", "--robots", "1"],
    ["run", "{script}", "--seed", "-1"],
    ["example", "coverage", "--seed", "-3"],
    ["robots", "--seed", "-1", "--duration", "1"],
    ["calibrate", "camera", "--write-synthetic", "{script}.d", "--seed", "-1"],
])
def test_bad_arguments_give_one_line_and_exit_2(argv, tmp_path, capsys):
    script = tmp_path / "ok.py"
    script.write_text("def experiment(arena):\n    while True:\n        arena.step()\n")
    assert main([a.format(script=script) for a in argv]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    if "--seed" in argv:
        assert "--seed must be a non-negative integer" in err


def test_sys_exit_zero_ends_the_run_normally(tmp_path, capsys):
    script = tmp_path / "done.py"
    script.write_text(textwrap.dedent("""
        import sys
        def experiment(arena):
            arena.step()
            sys.exit(0)
    """))
    assert main(["run", str(script), "--robots", "2"]) == 0
    assert "steps: 1 " in capsys.readouterr().out
