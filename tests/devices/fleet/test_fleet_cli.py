"""``swarmdeck fleet status|setup|dock|release`` on a simulated arena: tables and JSON, exit codes, and bad input
(malformed POSES.csv, poses outside or too close, too few charged robots, a missing robot source) as one line."""
from __future__ import annotations

import json

import pytest

from swarmdeck.console.cli import main


def test_status_lists_every_robot_docked_and_charging(capsys) -> None:
    assert main(["fleet", "status", "--simulated", "3", "--charge", "0.6"]) == 0
    out = capsys.readouterr().out
    assert "3.84 V" in out and "60%" in out and "slot 2" in out and "3/3 docked · ready" in out
    assert main(["fleet", "status", "--simulated", "2", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["ready"] and [r["docked_slot"] for r in doc["robots"]] == [0, 1]
    assert all(r["charging"] and r["charge"] == pytest.approx(1.0) for r in doc["robots"])


def test_setup_reports_the_assignment_and_the_pose_errors(tmp_path, capsys) -> None:
    poses = tmp_path / "start.csv"
    poses.write_text("x,y,theta\n-1.0,-0.45,0.0\n-0.6,-0.5,1.57\n")
    assert main(["fleet", "setup", str(poses), "--simulated", "4", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["ok"] and doc["collisions"] == 0 and len(doc["assignment"]) == 2
    assert doc["max_position_error"] <= 0.02 and doc["max_heading_error_deg"] <= 5.0


def test_a_setup_that_runs_out_of_time_exits_1_naming_the_robots(tmp_path, capsys) -> None:
    poses = tmp_path / "far.csv"
    poses.write_text("1.2,0.6,3.0\n")
    assert main(["fleet", "setup", str(poses), "--simulated", "2", "--time-limit", "1"]) == 1
    err = capsys.readouterr().err
    assert "did not finish within 1 s: robot" in err and "every robot stopped" in err


@pytest.mark.parametrize("body, argv, message", [
    ("0,0\n", [], "line 1: expected 3 values"),
    ("0,0,north\n", [], "line 1: not numbers"),
    ("2.5,0,0\n", [], "start pose 0 (2.500, 0.000, 0.000) is outside the arena"),
    ("0,0,0\n0.05,0.05,0\n", [], "start poses 0 and 1 are 0.071 m apart"),
    ("-0.5,0,0\n0,0,0\n0.5,0,0\n", ["--charge", "0.3"], "robot 0: battery 30% < 50%"),
    (None, [], "cannot read"),
])
def test_bad_input_is_one_line(tmp_path, capsys, body, argv, message) -> None:
    path = tmp_path / "poses.csv"
    if body is not None:
        path.write_text(body)
    assert main(["fleet", "setup", str(path), "--simulated", "3", *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_console_starts_docked_robots_with_batteries(tmp_path, capsys) -> None:
    from swarmdeck.console.recording.reader import open_recording

    path = tmp_path / "docked.mcap"
    assert main(["console", "--port", "0", "--duration", "0.3", "--robots", "3", "--start", "docked", "--no-inputs",
                 "--behaviour", "rendezvous", "--record", str(path)]) == 0
    with open_recording(path) as r:
        first = next(f for _, f in r.frames())
    assert first.charging.all() and (first.battery > 4.19).all()


@pytest.mark.parametrize("argv, message", [
    (["fleet", "status"], "--robots-via mqtt://HOST:PORT or --simulated N"),
    (["fleet", "setup", "--simulated", "2"], "setup needs POSES.csv"),
    (["fleet", "dock", "x.csv", "--simulated", "2"], "dock takes no POSES.csv"),
    (["fleet", "status", "--simulated", "2", "--ids", "1"], "--ids applies to dock only"),
    (["fleet", "status", "--simulated", "2", "--charge", "1.5"], "--charge must be"),
    (["fleet", "dock", "--simulated", "2", "--ids", "7"], "no robot(s) [7] in the arena"),
    (["console", "--start", "docked", "--robots-via", "mqtt://127.0.0.1:1", "--no-inputs"],
     "physical robots start where they are"),
    (["console", "--start", "docked", "--robots", "60", "--no-inputs", "--no-record"], "the charging strips have 50"),
])
def test_usage_errors(capsys, argv, message) -> None:
    assert main(argv) == 2
    assert message in capsys.readouterr().err
