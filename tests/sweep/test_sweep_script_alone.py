"""The script's side: run alone it gets its defaults; a runner's values override them; an undeclared name or a value
of another kind is an error naming it; record_metrics alone checks its values and prints nothing."""
import json
import subprocess
import sys
from pathlib import Path

import pytest

from swarmdeck.devices.experiment_params import PARAMS_ENV, ParamError, check_metrics, overrides_from_env, resolve

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "sweep_gain.py"

ALONE = """
from swarmdeck.devices import params, record_metrics
p = params(gain=1.0, robots=4, label="ring")
print("values", p.gain, p.robots, p.label, p["gain"])
record_metrics(spread=0.25)
"""


def _run(tmp_path):
    script = tmp_path / "alone.py"
    script.write_text(ALONE)
    env = {"PATH": "/usr/bin:/bin"}  # no SWARMDECK_PARAMS: as a researcher runs it
    return subprocess.run([sys.executable, str(script)], capture_output=True, text=True, env=env, timeout=120)


def test_the_script_runs_alone_with_its_defaults(tmp_path):
    done = _run(tmp_path)
    assert done.returncode == 0, done.stderr
    assert "values 1.0 4 ring 1.0" in done.stdout
    assert done.stderr == ""  # record_metrics alone: checked, nothing printed


def test_a_runner_overrides_the_defaults_through_the_environment(monkeypatch):
    from swarmdeck.devices import params

    monkeypatch.setenv(PARAMS_ENV, json.dumps({"gain": 2, "robots": 8.0}))
    p = params(gain=1.0, robots=4, label="ring")
    assert (p.gain, p.robots, p.label) == (2.0, 8, "ring") and type(p.robots) is int  # 8.0 is an int's 8
    monkeypatch.setenv(PARAMS_ENV, json.dumps({"gian": 2}))
    with pytest.raises(ParamError, match="'gian' not declared by the script \\(it declares: gain, robots, label\\)"):
        params(gain=1.0, robots=4, label="ring")


def test_an_ill_typed_value_is_named():
    with pytest.raises(ParamError, match="robots is a int"):
        resolve({"robots": 4}, {"robots": 2.5})
    with pytest.raises(ParamError, match="JSON object"):
        overrides_from_env({PARAMS_ENV: "[1, 2]"})


def test_metrics_are_checked():
    assert check_metrics({"a": 1, "b": 2.5}) == {"a": 1.0, "b": 2.5}
    for bad in ({"a": float("nan")}, {"a": "x"}, {"no good": 1.0}, {"a": True}, {f"m{i}": 1.0 for i in range(65)}):
        with pytest.raises(ParamError):
            check_metrics(bad)


def test_the_shipped_example_declares_what_the_docs_sweep():
    from swarmdeck.devices.experiment_params import declared_in_source

    assert declared_in_source(EXAMPLE.read_text()) == {"gain": 0.1, "goal": 0.4}


def test_swarmdeck_run_gives_one_point_and_gives_the_environment_back(tmp_path, capsys, monkeypatch):
    import os

    from swarmdeck.console.cli import main

    monkeypatch.delenv(PARAMS_ENV, raising=False)
    script = tmp_path / "one.py"
    script.write_text("from swarmdeck.devices import params\np = params(gain=1.0)\n"
                      "def experiment(arena):\n    print('gain is', p.gain)\n")
    assert main(["run", str(script), "--param", "gain=2.5", "--robots", "2", "--duration", "0.1"]) == 0
    assert "gain is 2.5" in capsys.readouterr().out and PARAMS_ENV not in os.environ
    assert main(["run", str(script), "--param", "gain=1:2:3", "--robots", "2", "--duration", "0.1"]) == 2
    assert "one value per parameter here" in capsys.readouterr().err
