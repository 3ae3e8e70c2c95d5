"""Chunks close by frame count, not by wall time: a slow live console (frames arriving one by one,
the writer idle in between) writes the same keyframes as a fast one (every frame queued at once).

Before: the recorder closed a chunk every ``flush_interval`` s of wall time, so a console whose
ticks reached the writer slowly wrote more, smaller chunks (more keyframes, more bytes per frame).
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import pytest
from mcap.records import Chunk
from mcap.stream_reader import StreamReader, breakup_chunk
from recording_synth import simulated_frames

from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
from swarmdeck.console.recording.schemas import TOPIC_FRAME


def keyframe_ticks(path: Path) -> list[int]:
    """The tick of the first frame of every chunk (each chunk starts with a keyframe)."""
    out = []
    with open(path, "rb") as fh:
        channels: dict[int, str] = {}
        for rec in StreamReader(fh, emit_chunks=True).records:
            if isinstance(rec, Chunk):
                msgs = [m for m in breakup_chunk(rec) if hasattr(m, "topic") or hasattr(m, "data")]
                for m in msgs:
                    if hasattr(m, "topic"):
                        channels[m.id] = m.topic
                frames = [m for m in msgs if hasattr(m, "channel_id") and channels.get(m.channel_id) == TOPIC_FRAME]
                if frames:
                    out.append(json.loads(frames[0].data)["tick"])
    return out


@pytest.fixture(scope="module")
def frames():
    return list(simulated_frames(n_robots=6, n_ticks=48, dt=1 / 30))


def test_a_slow_console_writes_the_keyframes_a_fast_one_writes(tmp_path, frames):
    # chunk_frames: the default, 20. The slow run spans ≈ 3.4 s > flush_interval (the old wall-time rule closes a
    # chunk in it) while each gap (≈ 0.07 s) stays far below it, so a loaded machine's stall cannot close one either
    config = RecorderConfig(foxglove=False, flush_interval=3.0)
    fast = tmp_path / "fast.mcap"
    with Recorder(fast, config=config) as rec:
        for f in frames:
            rec.write_frame(f)
    slow = tmp_path / "slow.mcap"
    with Recorder(slow, config=config) as rec:
        for k, f in enumerate(frames):  # ≈ 3.4 s of wall time in all, one frame at a time
            rec.write_frame(f)
            deadline = time.monotonic() + 60
            while rec.status().frames <= k and time.monotonic() < deadline:  # the writer has it
                time.sleep(0.005)
            time.sleep(0.07)
    assert keyframe_ticks(fast) == keyframe_ticks(slow) == list(range(0, 48, RecorderConfig().chunk_frames))


def test_chunk_frames_sets_the_cadence(tmp_path, frames):
    path = tmp_path / "five.mcap"
    with Recorder(path, config=RecorderConfig(foxglove=False, chunk_frames=5)) as rec:
        for f in frames:
            rec.write_frame(f)
    assert keyframe_ticks(path) == list(range(0, 48, 5))


@pytest.mark.parametrize("bad", [0, -1, 2.5, True])
def test_a_bad_chunk_frames_is_refused_by_name(bad):
    with pytest.raises(ValueError, match="chunk_frames"):
        RecorderConfig(chunk_frames=bad)
