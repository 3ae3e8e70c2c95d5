"""Export: CSV holds every pose and command exactly; the HTML replay embeds a viser recording of the frames."""
from __future__ import annotations

import base64
import csv
import re

import msgspec
import numpy as np
import pytest
import zstandard
from recording_synth import as_recorded, simulated_frames

from swarmdeck.console.recording.export_csv import ROBOT_COLUMNS, export_csv
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder
from swarmdeck.console.web.export_html import export_html


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    path = tmp_path_factory.mktemp("export") / "e.mcap"
    frames = list(simulated_frames(n_robots=5, n_ticks=40, dt=0.05, seed=6))
    with Recorder(path) as rec:
        for f in frames:
            rec.write_frame(f)
    return path, frames


def test_csv_has_every_robot_at_every_frame_exactly(tmp_path, recorded):
    path, frames = recorded
    with open_recording(path) as r:
        robots_csv, frames_csv, n = export_csv(r, tmp_path / "csv")
    assert n == len(frames)
    rows = np.loadtxt(robots_csv, delimiter=",", skiprows=1)
    assert open(robots_csv).readline().strip().split(",") == list(ROBOT_COLUMNS)
    assert rows.shape == (len(frames) * 5, len(ROBOT_COLUMNS))
    col = {c: i for i, c in enumerate(ROBOT_COLUMNS)}
    want = np.concatenate([np.column_stack((f.poses, f.v, f.w, g.nominal, g.safe))
                           for f, g in zip(frames, map(as_recorded, frames))])  # poses, v, w exact
    got = rows[:, [col[c] for c in ("x", "y", "theta", "v", "w", "nominal_x", "nominal_y", "safe_x", "safe_y")]]
    assert np.array_equal(got, want)  # 17 significant digits: exact doubles
    assert np.array_equal(rows[:, col["id"]], np.tile(np.arange(5), len(frames)))
    assert np.array_equal(rows[:, col["tick"]], np.repeat([f.tick for f in frames], 5))
    with open(frames_csv, newline="") as fh:
        table = list(csv.DictReader(fh))
    assert len(table) == len(frames)
    assert [float(t["cost_H"]) for t in table] == [f.coverage.cost_H for f in frames]
    assert table[25]["events"] == "tick 25: operator note"


def test_csv_window(tmp_path, recorded):
    path, frames = recorded
    with open_recording(path) as r:
        _, _, n = export_csv(r, tmp_path / "w", start=0.5, end=1.0)
    assert n == 10


def test_html_replay_embeds_the_frames(tmp_path, recorded):
    path, frames = recorded
    with open_recording(path) as r:
        out, drawn = export_html(r, tmp_path / "replay.html", fps=10.0)
    assert drawn == 20  # 2 s at 10 fps out of 20 fps frames
    html = out.read_text()
    data = base64.b64decode(re.search(r'window.__VISER_EMBED_DATA__="([^"]+)"', html).group(1))
    inner = zstandard.ZstdDecompressor().decompress(data[8:], max_output_size=int.from_bytes(data[:8], "little"))
    n = int.from_bytes(inner[:8], "little")
    payload = msgspec.msgpack.decode(inner[8:8 + n])
    assert payload["durationSeconds"] == pytest.approx((drawn - 1) * 0.1, abs=1e-6)
    names = [m.get("name") for _, m in payload["messages"]]
    assert "/robots" in names and "/voronoi" in names
    times = sorted({t for t, _ in payload["messages"]})
    assert len(times) == drawn  # one batch of scene updates per drawn frame
