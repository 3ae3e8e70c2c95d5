"""The commands: sessions, info, export, play — output and clear errors."""
from __future__ import annotations

import json

import pytest
from recording_synth import write_synthetic_session

from swarmdeck.console.cli import main
from swarmdeck.console.recording.schemas import RECORDING_FORMAT


@pytest.fixture(scope="module")
def sessions(tmp_path_factory):
    d = tmp_path_factory.mktemp("sessions")
    write_synthetic_session(d / "a.mcap", n_robots=4, seconds=1.0, dt=0.05)
    write_synthetic_session(d / "b.mcap", n_robots=7, seconds=2.0, dt=0.05)
    (d / "junk.mcap").write_text("not a recording")
    return d


def test_sessions_lists_every_recording(sessions, capsys):
    assert main(["sessions", str(sessions)]) == 0
    out = capsys.readouterr().out
    lines = {ln.split()[0]: ln for ln in out.splitlines()[1:]}
    assert set(lines) == {"a.mcap", "b.mcap", "junk.mcap"}
    assert " 7 " in lines["b.mcap"] and "1.9 s" in lines["b.mcap"] and lines["b.mcap"].rstrip().endswith("ok")
    assert "unreadable: " in lines["junk.mcap"] and "not an MCAP file" in lines["junk.mcap"]


def test_sessions_of_a_missing_folder_is_a_usage_error(tmp_path, capsys):
    assert main(["sessions", str(tmp_path / "nope")]) == 2
    assert "is not a folder" in capsys.readouterr().err


def test_info_json(sessions, capsys):
    assert main(["info", str(sessions / "b.mcap"), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["frames"] == 40 and s["robots"] == list(range(7)) and s["closed_cleanly"]
    assert s["config"] == {"source": "synthetic", "seed": 0} and s["recording_format"] == RECORDING_FORMAT


def test_info_on_a_foreign_file_says_why(sessions, capsys):
    assert main(["info", str(sessions / "junk.mcap")]) == 2
    assert "not an MCAP file" in capsys.readouterr().err


def test_export_needs_a_target_and_writes_csv(sessions, tmp_path, capsys):
    assert main(["export", str(sessions / "a.mcap")]) == 2
    assert "say what to export: --csv DIR, --html OUT.html and/or --video OUT.mp4" in capsys.readouterr().err
    assert main(["export", str(sessions / "a.mcap"), "--csv", str(tmp_path / "out")]) == 0
    assert (tmp_path / "out" / "robots.csv").exists() and "wrote 20 frames" in capsys.readouterr().out


def test_play_rejects_bad_options_before_serving(sessions, capsys):
    assert main(["play", str(sessions / "a.mcap"), "--rate", "8"]) == 2
    assert "--rate must be between 0.1 and 4" in capsys.readouterr().err
    assert main(["play", str(sessions / "junk.mcap")]) == 2
    assert "not an MCAP file" in capsys.readouterr().err
