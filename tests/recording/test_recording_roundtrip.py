"""Round trip: a recorded simulated run reads back frame for frame, datagram for datagram, event for event."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from recording_synth import as_recorded, simulated_frames

from swarmdeck.console.recording.codec import CODEC_FORMAT
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
from swarmdeck.console.runtime.frame import BarrierFrame


@pytest.fixture(scope="module")
def frames():
    out = list(simulated_frames(n_robots=7, n_ticks=60, seed=4))
    # non-finite numbers and NaN params must survive too
    out[5] = dataclasses.replace(out[5], barrier=BarrierFrame(min_distance=math.nan, min_wall_clearance=-math.inf,
                                                              intervention=np.zeros(7)),
                                 params={"gamma": math.inf, "law": "tvd-d1"})
    return out


@pytest.mark.parametrize("compression", ["zstd", "lz4", "none"])
def test_every_frame_reads_back_equal(tmp_path, frames, compression):
    path = tmp_path / "run.mcap"
    rec = Recorder(path, {"robots": list(range(7)), "config": {"note": "round trip"}},
                   RecorderConfig(compression=compression, chunk_size=20_000))
    peers = [("127.0.0.1", 50000 + i) for i in range(len(frames))]
    for i, f in enumerate(frames):
        assert rec.write_frame(f)
        rec.write_datagram(bytes([i, 255 - i, 0, 7]) * (i + 1), peers[i], "udp", f.time + 0.001, "tuio")
        if i % 20 == 0:
            rec.write_event(f.time, "operator", f"note {i}")
    status = rec.close()
    assert status.state == "closed" and status.frames == len(frames) and status.dropped == 0
    assert status.datagrams == len(frames)

    with open_recording(path) as r:
        assert r.indexed and not r.warnings and r.n_chunks > 1
        got = list(r.frames())
        assert [f.to_dict() for _, f in got] == [as_recorded(f).to_dict() for f in frames]
        for (_, g), f in zip(got, frames):  # poses and the commands sent: bit for bit
            assert np.array_equal(g.poses, f.poses) and np.array_equal(g.v, f.v) and np.array_equal(g.w, f.w)
        # recording time is the frame clock relative to the first frame (ns resolution)
        assert all(abs(t - (f.time - frames[0].time)) < 2e-9 for t, f in got)
        dgs = list(r.datagrams())
        assert [d.data for d in dgs] == [bytes([i, 255 - i, 0, 7]) * (i + 1) for i in range(len(frames))]
        assert [d.peer for d in dgs] == peers and {d.listener for d in dgs} == {"tuio"}
        assert [d.t for d in dgs] == [f.time + 0.001 for f in frames]
        ops = [e.text for e in r.events() if e.kind == "operator"]
        assert ops == [f"note {i}" for i in range(0, len(frames), 20)]
        frame_events = [e.text for e in r.events() if e.kind == "frame"]
        assert frame_events == [e for f in frames for e in f.events]
        cfg = r.config()
        assert cfg["robots"] == list(range(7)) and cfg["config"] == {"note": "round trip"}
        assert cfg["frame_format"] == CODEC_FORMAT and "numpy" in cfg["versions"]
        assert r.count_frames() == len(frames)


def test_close_is_idempotent_and_late_writes_are_refused(tmp_path, frames):
    rec = Recorder(tmp_path / "a.mcap")
    rec.write_frame(frames[0])
    first = rec.close()
    assert rec.close() == first
    assert rec.write_frame(frames[1]) is False
    with open_recording(tmp_path / "a.mcap") as r:
        assert [f.tick for _, f in r.frames()] == [frames[0].tick]


def test_default_path_is_a_fresh_timestamped_file_in_sessions(tmp_path):
    from swarmdeck.console.recording.recorder import default_path

    p1 = default_path(tmp_path, now=1_800_000_000.0)
    assert p1.parent == tmp_path and p1.name == "20270115-080000.mcap"
    p1.write_bytes(b"")
    assert default_path(tmp_path, now=1_800_000_000.0).name == "20270115-080000-1.mcap"
