"""``swarmdeck compare``: the metrics of closed-form recordings (compare_synth), the table and its JSON, runs of
different arenas and robot counts (compared, and what differs said), a file given twice, a corrupt or cut
recording (a clear error naming the file, or the readable part with a warning)."""
from __future__ import annotations

import json
import os

import pytest
from compare_synth import straight_run

from swarmdeck.console.cli import main
from swarmdeck.console.recording.metrics import differences, frame_setup, run_metrics
from swarmdeck.console.recording.reader import open_recording


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("compare")
    a = straight_run(d / "a.mcap", 33, events={8: "go"}, intervening=range(10, 20), failed=[5], estop=[30, 31])
    # B: 5 robots on a 2.4 × 1.6 m arena, slower (no contact: robot 1 stops 0.3 m short of robot 0)
    b = straight_run(d / "b.mcap", 33, n=5, speed=0.1, bounds=(-1.2, 1.2, -0.8, 0.8))
    long = straight_run(d / "long.mcap", 200, chunk_size=2000)
    (d / "junk.mcap").write_bytes(b"\x89MCAP0\r\n" + b"\0" * 64)
    return d, a, b, long


def test_the_metrics_of_a_closed_form_run(files):
    _, a, _, _ = files
    with open_recording(a) as rec:
        m = run_metrics(rec)
    assert (m.duration_s, m.frames, m.robots, m.dt) == (2.0, 33, 3, 0.0625)
    # robot 1 at x = 0.5 − 0.2 t reaches 0.1 m < 0.11 m (a diameter) from robot 0 only in the last frame
    assert (m.contacts, m.contact_frames) == (1, 1) and m.min_distance_m == pytest.approx(0.1)
    assert (m.interventions, m.intervention_frames, m.filter_failures, m.stopped_frames, m.events) == (10, 10, 1, 2, 1)
    assert m.coverage_cost_final == pytest.approx(1 + 0.1 * 32) and m.coverage_cost_mean == pytest.approx(1 + 0.1 * 16)
    # robot 1 drives 0.2 m/s for 2 s except the two e-stopped ticks' … poses, which keep the closed form: 0.4 m
    assert m.distance_m == pytest.approx(0.4) and m.distance_per_robot_m == pytest.approx(0.4 / 3)
    assert m.warnings == () and m.arena == "3.2 × 2 at (-1.6, -1)"


def test_compare_prints_a_column_per_run_and_what_differs(files, capsys):
    _, a, b, _ = files
    assert main(["compare", a, b]) == 0
    out = capsys.readouterr().out
    rows = {line[:37].strip(): line[37:].split() for line in out.splitlines() if line[:1].isalpha() and "  " in line}
    assert rows["robots"] == ["3", "5"] and rows["contacts (onsets)"] == ["1", "0"]
    assert rows["minimum distance (m, centres)"] == ["0.1", "0.3"]  # B: robots 2-4 0.3 m apart, robot 1 ends 0.3 short
    assert rows["distance travelled (m, all robots)"] == ["0.4", "0.2"]
    assert f"A: {a}" in out and f"B: {b}" in out
    assert "note: arena (m) differ: A 3.2 × 2 at (-1.6, -1); B 2.4 × 1.6 at (-1.2, -0.8)" in out
    assert "note: robots differ: A 3; B 5" in out


def test_compare_json_names_every_metric(files, capsys):
    _, a, b, _ = files
    assert main(["compare", a, b, "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert [r["name"] for r in got["runs"]] == ["A", "B"]
    assert got["runs"][0]["interventions"] == 10 and got["runs"][1]["coverage_cost_final"] == pytest.approx(4.2)
    assert got["runs"][1]["bounds"] == [-1.2, 1.2, -0.8, 0.8]
    keys = {m["key"] for m in got["metrics"]}
    assert keys <= set(got["runs"][0]) and {"contacts", "min_distance_m", "distance_m"} <= keys
    assert got["differences"][:2] == ["arena (m) differ: A 3.2 × 2 at (-1.6, -1); B 2.4 × 1.6 at (-1.2, -0.8)",
                                      "robots differ: A 3; B 5"]


def test_runs_alike_have_no_differences(files):
    _, a, _, _ = files
    with open_recording(a) as rec:
        first = rec.first_frame
    assert first is not None and differences([frame_setup(first), frame_setup(first)]) == []


def test_one_file_given_twice_is_refused(files, capsys):
    d, a, _, _ = files
    assert main(["compare", a, a]) == 2
    assert f"{a} is given twice" in capsys.readouterr().err
    assert main(["play", a, os.path.join(str(d), ".", "a.mcap")]) == 2  # the same file by another name
    assert "is given twice (it is" in capsys.readouterr().err


def test_a_corrupt_recording_is_named(files, capsys):
    d, a, _, _ = files
    assert main(["compare", a, str(d / "junk.mcap")]) == 2
    err = capsys.readouterr().err
    assert "junk.mcap" in err and "damaged MCAP file" in err
    assert main(["play", a, str(d / "missing.mcap")]) == 2
    assert "missing.mcap: no such file" in capsys.readouterr().err


def test_a_cut_recording_is_compared_on_its_readable_part(files, tmp_path, capsys):
    _, a, _, long = files
    data = open(long, "rb").read()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    assert main(["compare", a, str(cut), "--json"]) == 0
    captured = capsys.readouterr()
    got = json.loads(captured.out)
    run = got["runs"][1]
    assert 0 < run["frames"] < 200 and run["warnings"] and "cut.mcap: file ends inside a record" in captured.err
    assert run["duration_s"] == pytest.approx((run["frames"] - 1) * 0.0625)


def test_play_with_bad_alignment_says_so_before_serving(files, capsys):
    _, a, b, _ = files
    assert main(["play", a, "--align", "t:1"]) == 2
    assert "--align lines up several recordings" in capsys.readouterr().err
    assert main(["play", a, b, "--align", "event:go"]) == 2
    assert "b.mcap: no event contains 'go'" in capsys.readouterr().err
    assert main(["play", a, b, "--align", "t:1", "--align", "t:2", "--align", "t:3"]) == 2
    assert "--align given 3 times for 2 recordings" in capsys.readouterr().err
