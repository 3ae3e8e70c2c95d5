"""``swarmdeck console`` from the command line, and its TOML configuration file."""
from __future__ import annotations

import pytest

from swarmdeck.console.cli import main
from swarmdeck.console.runtime.config import ConfigFileError, load_settings


def test_console_runs_headless_for_a_duration_and_prints_the_url(capsys) -> None:
    rc = main(["console", "--port", "0", "--duration", "0.5", "--robots", "5", "--no-inputs", "--seed", "1",
               "--no-record"])
    out = capsys.readouterr().out
    assert rc == 0
    assert "swarmdeck console: http://127.0.0.1:" in out and "5 robots, coverage" in out
    assert "ran " in out and "ticks" in out


def test_console_records_the_session(tmp_path, capsys) -> None:
    path = tmp_path / "run.mcap"
    rc = main(["console", "--port", "0", "--duration", "0.5", "--robots", "4", "--no-inputs", "--record", str(path)])
    assert rc == 0 and path.stat().st_size > 0
    assert f"recording to {path}" in capsys.readouterr().err


@pytest.mark.parametrize("argv, message", [
    (["console", "--behaviour", "dance", "--no-inputs"], "unknown behaviour"),
    (["console", "--robots", "0", "--no-inputs"], "--robots must be >= 1, got 0"),  # the flag, not n_robots
    (["console", "--duration", "-1", "--no-inputs"], "--duration"),
    (["console", "--behaviour", "script:/no/such/file.py", "--no-inputs"], "does not exist"),
])
def test_usage_errors_are_one_line(capsys, argv, message) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_config_file_sets_everything(tmp_path) -> None:
    p = tmp_path / "console.toml"
    p.write_text(
        '[console]\nport = 0\nrobots = 7\nbehaviour = "goto"\nseed = 3\n'
        '[behaviour]\nkappa = 2.0\nlaw = "lloyd"\ngoals = [[0.0, 0.0], [0.5, 0.5]]\ngoal_centre = [0.5, 0]\n'
        '[safety]\ngamma = 50\nsafety_distance = 0.2\n'
        '[density]\nmoving = false\nbump_sigma = 0.3\n'
    )
    s = load_settings(p)
    assert (s.port, s.loop.n_robots, s.loop.behaviour, s.loop.seed) == (0, 7, "goto", 3)
    assert s.loop.behaviour_params.kappa == 2.0 and s.loop.behaviour_params.goals == ((0.0, 0.0), (0.5, 0.5))
    assert s.loop.behaviour_params.goal_centre == (0.5, 0.0)
    assert s.loop.safety.gamma == 50.0 and s.loop.density.moving is False and s.inputs is None


@pytest.mark.parametrize("body, message", [
    ("[console]\nrobots = -3\n", "[console] robots"),
    ("[console]\nspeed = 3\n", "unknown key(s) ['speed'] in [console]"),
    ("[safety]\ngamma = 1e6\n", "[safety]: gamma"),
    ("[behaviour]\nlaw = 'magic'\n", "law"),
    ("[extras]\nx = 1\n", "unknown table(s) ['extras']"),
    ("[console\n", "not valid TOML"),
    ("[safety]\ngamma = 'strong'\n", "[safety]"),
    ("[behaviour]\ngoals = [[0, 'a']]\n", "[behaviour]"),
    ("[console]\nbounds = 3\n", "[console]"),
])
def test_bad_config_files_are_named(tmp_path, body, message) -> None:
    p = tmp_path / "bad.toml"
    p.write_text(body)
    with pytest.raises(ConfigFileError) as info:
        load_settings(p)
    assert message in str(info.value) and str(p) in str(info.value)


def test_config_errors_through_the_cli(tmp_path, capsys) -> None:
    p = tmp_path / "bad.toml"
    p.write_text("[safety]\nsafety_distance = 3\n")
    assert main(["console", "--config", str(p), "--no-inputs"]) == 2
    assert "safety_distance" in capsys.readouterr().err
    assert main(["console", "--config", str(tmp_path / "missing.toml"), "--no-inputs"]) == 2
