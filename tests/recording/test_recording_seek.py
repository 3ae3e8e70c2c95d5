"""Seeking: frame_at / frame_after / frame_before agree with a brute-force scan, indexed or scanned."""
from __future__ import annotations

import bisect
import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from recording_synth import simulated_frames

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig

N_FRAMES = 240


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """A file of many small chunks; datagrams interleaved slightly *before* each frame so chunk
    time ranges overlap the previous chunk's frames (as when input threads race the loop), and a
    few stamped a second late, so chunk start times are not monotonic."""
    d = tmp_path_factory.mktemp("seek")
    path = d / "seek.mcap"
    frames = list(simulated_frames(n_robots=4, n_ticks=N_FRAMES, dt=0.05, seed=2, coverage=False))
    rec = Recorder(path, config=RecorderConfig(chunk_size=3000))
    for k, f in enumerate(frames):
        rec.write_datagram(b"x" * 40, ("h", 1), "udp", f.time - 0.07)
        if k % 37 == 36:  # a datagram delivered a second late: chunk start times dip
            rec.write_datagram(b"late", ("h", 2), "udp", f.time - 1.0)
        rec.write_frame(f)
    rec.close()
    # the same data without DataEnd and summary (the file a crash leaves): the reader scans it
    data = path.read_bytes()
    summary_start = struct.unpack_from("<Q", data, len(data) - 8 - 29 + 9)[0]  # Footer.summary_start
    cut = d / "nosummary.mcap"
    cut.write_bytes(data[: summary_start - 13])  # DataEnd is 13 bytes
    times = [f.time - frames[0].time for f in frames]
    return path, cut, frames, times


def _expected_at(times, t):
    k = bisect.bisect_right(times, t + 1e-9) - 1
    return max(k, 0)


@pytest.mark.parametrize("which", [0, 1])
@settings(max_examples=30, deadline=None)
@given(t=st.floats(-1.0, N_FRAMES * 0.05 + 1.0, allow_nan=False))
def test_frame_at_is_the_last_frame_not_after_t(recorded, which, t):
    path, cut, frames, times = recorded
    with open_recording((path, cut)[which]) as r:
        assert r.n_chunks > 20 and r.indexed == (which == 0)
        rel, f = r.frame_at(t)
        k = _expected_at(times, t)
        assert f.tick == frames[k].tick
        assert abs(rel - times[k]) < 2e-9


def test_step_forward_and_backward_visits_every_frame_once(recorded):
    path, _, frames, times = recorded
    with open_recording(path) as r:
        ticks, pos = [r.frame_at(0.0)[1].tick], 0.0
        while (hit := r.frame_after(pos)) is not None:
            pos = hit[0]
            ticks.append(hit[1].tick)
        assert ticks == [f.tick for f in frames]
        back = [r.frame_at(pos)[1].tick]
        while (hit := r.frame_before(pos)) is not None:
            pos = hit[0]
            back.append(hit[1].tick)
        assert back == ticks[::-1]


def test_frames_in_a_window(recorded):
    path, _, frames, times = recorded
    with open_recording(path) as r:
        got = [f.tick for _, f in r.frames(2.0, 5.0)]
        assert got == [f.tick for f, t in zip(frames, times) if 2.0 - 1e-9 <= t < 5.0 - 1e-9]
        assert r.duration == pytest.approx(times[-1], abs=1e-9)
