"""Format-3 recordings: every chunk starts with a keyframe and decodes on its own.

The real recorder writes simulated and tracker-like frames; the mcap package's own reader, chunk
by chunk with nothing carried over, decodes every frame bit for bit — also when chunks are closed
by size (one frame each) rather than by time. Seeking into the middle of a file just opened gives
the frames a linear read gives. A file cut off anywhere plays, and ``recover`` rewrites, every
frame up to the last intact chunk. A damaged predicted frame costs the frames after it in its
chunk only. The stored format-2 and format-3 files still open (the format-3 file pins the
prediction: a predictor that computed other bits would fail its frames' checksums).
"""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.records import Channel, Chunk, Message
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import Writer
from test_recording_prediction import walk

from swarmdeck.console.recording.codec import decode_frame, encode_frame, unpack_array
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
from swarmdeck.console.recording.recover import recover
from swarmdeck.console.recording.schemas import FRAME_SCHEMA, METADATA_NAME, PROFILE, TOPIC_FRAME

DATA = Path(__file__).resolve().parents[1] / "data"
EXACT = ("ids", "poses", "v", "w")


def same(a, b) -> bool:
    return all(getattr(a, k).tobytes() == getattr(b, k).tobytes() for k in EXACT) and a.tick == b.tick


def record(path: Path, frames, **config) -> Path:
    with Recorder(path, config=RecorderConfig(foxglove=False, **config)) as rec:
        for f in frames:
            rec.write_frame(f)
    return path


def chunks_of(path: Path) -> list[list[bytes]]:
    """The frame messages of every chunk, with the mcap package's stream reader."""
    out: list[list[bytes]] = []
    topics: dict[int, str] = {}
    with open(path, "rb") as fh:
        for rec in StreamReader(fh, emit_chunks=True).records:
            if isinstance(rec, Channel):
                topics[rec.id] = rec.topic
            if isinstance(rec, Chunk):
                inner = breakup_chunk(rec)
                topics.update({r.id: r.topic for r in inner if isinstance(r, Channel)})
                out.append([r.data for r in inner if isinstance(r, Message) and topics.get(r.channel_id) == TOPIC_FRAME])
    return out


@pytest.fixture(scope="module")
def frames():
    # 80 simulated frames, then a tracker's frames after a missed tick (a gap: a keyframe there)
    tracked = [dataclasses.replace(f, tick=81 + f.tick, time=(81 + f.tick) * f.dt) for f in walk(40, 40, 0.001, seed=5)]
    return walk(40, 80, 0.0, seed=4) + tracked


@pytest.fixture(scope="module")
def recorded(tmp_path_factory, frames):
    return record(tmp_path_factory.mktemp("keyframes") / "k.mcap", frames)


@pytest.mark.parametrize("config", [{}, {"chunk_size": 1500}], ids=["by time", "by size"])
def test_every_chunk_starts_with_a_keyframe_and_decodes_alone(tmp_path, frames, config):
    path = record(tmp_path / "c.mcap", frames, **config)
    got = []
    chunks = chunks_of(path)
    for messages in chunks:
        assert messages and b'"pred"' not in messages[0]
        previous = None
        for m in messages:  # nothing from an earlier chunk
            previous = decode_frame(m, previous)
            got.append(previous)
    assert len(got) == len(frames) and all(same(g, f) for g, f in zip(got, frames))
    predicted = sum(b'"pred"' in m for c in chunks for m in c)
    if config:  # a frame (≈ 2.2 kB) fills a chunk: every frame is a keyframe
        assert len(chunks) == len(frames) and predicted == 0
    else:  # chunks of chunk_frames frames (20: ≈ 0.67 s at 30 Hz); the gap before the tracker's frames
        keyframes = {json.loads(m)["tick"] for c in chunks for m in c if b'"pred"' not in m}
        assert keyframes == {json.loads(c[0])["tick"] for c in chunks} | {81}
        assert len(chunks) >= len(frames) // (RecorderConfig().chunk_frames + 1)


def test_seeking_into_the_middle_gives_the_frames_a_linear_read_gives(recorded, frames):
    with open_recording(recorded) as r:
        linear = list(r.frames())
    assert len(linear) == len(frames) and all(same(g, f) for (_, g), f in zip(linear, frames))
    for k in (61, 37, 100, 8, 9, 119, 79, 80):
        with open_recording(recorded) as r:  # a fresh file: nothing decoded before the seek
            t, fr = r.frame_at(linear[k][0] + 1e-4)
            assert t == linear[k][0] and same(fr, linear[k][1])
            nxt = r.frame_after(linear[k][0])
            assert nxt is None if k == len(linear) - 1 else same(nxt[1], linear[k + 1][1])
            before = r.frame_before(linear[k][0])
            assert same(before[1], linear[k - 1][1])


def test_a_cut_off_file_plays_and_recovers_up_to_its_last_intact_chunk(tmp_path, recorded, frames):
    data = recorded.read_bytes()
    with open(recorded, "rb") as fh:
        index = sorted(make_reader(fh).get_summary().chunk_indexes, key=lambda c: c.chunk_start_offset)
    cuts = [c.chunk_start_offset + c.chunk_length // 2 for c in index[1::3]] + [index[-1].chunk_start_offset + 1]
    for cut in cuts:
        intact = [c for c in index if c.chunk_start_offset + c.chunk_length <= cut]
        n = len(intact)  # every chunk holds frames
        p = tmp_path / f"cut{cut}.mcap"
        p.write_bytes(data[:cut])
        with open_recording(p) as r:
            got = [f for _, f in r.frames()]
            assert not r.indexed and r.warnings
        want = [f for msgs in chunks_of(recorded)[:n] for f in msgs]
        assert len(got) == len(want) > 0 and all(same(g, f) for g, f in zip(got, frames))
        report = recover(p)
        assert report.chunks == n
        with open_recording(report.output) as r:
            assert r.indexed and not r.warnings
            back = [f for _, f in r.frames()]
        assert len(back) == len(got) and all(same(g, f) for g, f in zip(back, got))


def test_a_file_rechunked_by_another_tool_still_reads_every_frame(tmp_path, recorded, frames):
    """Copied by the mcap package's writer into ≈ 20 kB chunks: chunks that start inside a run of
    predicted frames read their first frames from the last frame of the chunk before."""
    path = tmp_path / "rechunked.mcap"
    with open(recorded, "rb") as src, open(path, "wb") as fh:
        reader = make_reader(src)
        w = Writer(fh, chunk_size=20_000)
        w.start(profile=PROFILE, library="another tool")
        for m in reader.iter_metadata():
            w.add_metadata(m.name, m.metadata)
        ids: dict[int, int] = {}
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if channel.id not in ids:
                sid = w.register_schema(schema.name, schema.encoding, schema.data)
                ids[channel.id] = w.register_channel(channel.topic, channel.message_encoding, sid)
            w.add_message(ids[channel.id], log_time=message.log_time, data=message.data, publish_time=message.publish_time)
        w.finish()
    starts = [c[0] for c in chunks_of(path)]
    assert sum(b'"pred"' in m for m in starts) >= 3  # the case under test
    with open_recording(path) as r:
        got = [f for _, f in r.frames()]
        assert not r.warnings and len(got) == len(frames) and all(same(g, f) for g, f in zip(got, frames))
    by_tick = {f.tick: f for f in frames}
    for m in starts:
        want = by_tick[json.loads(m)["tick"]]
        with open_recording(path) as r:  # a fresh file: seek straight into that chunk
            _, fr = r.frame_at(want.time - frames[0].time + 1e-4)
            assert same(fr, want) and not r.warnings


def test_a_damaged_predicted_frame_costs_only_the_rest_of_its_chunk(tmp_path, frames):
    """Chunk 1: frames 0–5 with frame 2's residuals damaged; chunk 2: frames 6–9."""
    path = tmp_path / "d.mcap"
    with open(path, "wb") as fh:
        w = Writer(fh)
        w.start(profile=PROFILE, library="test")
        w.add_metadata(METADATA_NAME, {"recording_format": "3", "frame_format": "3"})
        ch = w.register_channel(TOPIC_FRAME, "json", w.register_schema("swarmdeck.Frame", "jsonschema",
                                                                     json.dumps(FRAME_SCHEMA).encode()))
        for k, f in enumerate(frames[:10]):
            msg = json.loads(encode_frame(f, None if k in (0, 6) else frames[k - 1]))
            if k == 2:
                msg["poses"] = json.loads(encode_frame(frames[3], frames[2]))["poses"]
            w.add_message(ch, log_time=1_000_000 + k * 33_000_000, data=json.dumps(msg).encode(),
                          publish_time=0)
            if k == 5:
                w.flush()
        w.finish()
    with open_recording(path) as r:
        got = [f for _, f in r.frames()]
        assert [f.tick for f in got] == [0, 1, 6, 7, 8, 9] and all(same(g, frames[g.tick]) for g in got)
        assert any("fail their checksum" in m for m in r.warnings)
        assert any("predicted from tick 2" in m for m in r.warnings)


def test_stored_format_2_and_3_recordings_open():
    for name, fmt, n in (("recording_format2.mcap", 2, 30), ("recording_format3.mcap", 3, 40)):
        with open_recording(DATA / name) as r:
            assert r.metadata["recording_format"] == fmt == r.metadata["frame_format"]
            got = [f for _, f in r.frames()]
            assert len(got) == n and not r.warnings
            assert [e.text for e in r.events() if e.kind == "operator"] == ["e-stop"]
            assert got[-1].coverage is not None and len(got[-1].coverage.cell_offsets) == got[-1].n + 1
        chunks = chunks_of(DATA / name)
        assert sum(len(c) for c in chunks) == n
        if fmt == 2:  # self-contained frames: the stored binary arrays are what the reader returns
            for m, g in zip((m for c in chunks for m in c), got):
                d = json.loads(m)
                assert all(unpack_array(d[k], k).tobytes() == getattr(g, k).tobytes() for k in EXACT)
        else:  # the chunks start with keyframes; the predicted frames passed their checksums above
            assert all(b'"pred"' not in c[0] for c in chunks)
            assert sum(b'"pred"' in m for c in chunks for m in c) == n - len(chunks)
            assert np.isfinite(got[-1].poses).all()
