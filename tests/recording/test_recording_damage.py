"""Bad files: truncated, corrupted, foreign, newer — a clear message, and everything before the damage plays."""
from __future__ import annotations

import json

import pytest
from mcap.reader import make_reader
from mcap.writer import Writer
from recording_synth import as_recorded, simulated_frames

from swarmdeck.console.recording.reader import RecordingError, open_recording
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig


@pytest.fixture(scope="module")
def clean(tmp_path_factory):
    d = tmp_path_factory.mktemp("damage")
    path = d / "clean.mcap"
    frames = list(simulated_frames(n_robots=5, n_ticks=120, seed=9, coverage=False))
    rec = Recorder(path, config=RecorderConfig(chunk_size=2500))
    for f in frames:
        rec.write_frame(f)
    rec.close()
    with open(path, "rb") as fh:
        summary = make_reader(fh).get_summary()
    chunks = sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset)
    return path, frames, chunks


def _dicts(rec):
    return [f.to_dict() for _, f in rec.frames()]


def _frames_in(chunks, frames):
    """Number of frames whose log time falls inside ``chunks`` (frames are in time order)."""
    if not chunks:
        return 0
    start = frames[0].time
    end = (max(c.message_end_time for c in chunks) - chunks[0].message_start_time) / 1e9
    return sum(1 for f in frames if f.time - start <= end + 1e-9)


def test_truncated_anywhere_after_the_metadata_plays_a_prefix(tmp_path, clean):
    path, frames, chunks = clean
    data = path.read_bytes()
    want = [as_recorded(f).to_dict() for f in frames]
    first_chunk = chunks[0].chunk_start_offset
    cuts = sorted({first_chunk, *range(first_chunk + 1, len(data), max(1, (len(data) - first_chunk) // 17)),
                   len(data) - 1})
    for cut in cuts:
        p = tmp_path / f"cut{cut}.mcap"
        p.write_bytes(data[:cut])
        with open_recording(p) as r:
            got = _dicts(r)
            complete = [c for c in chunks if c.chunk_start_offset + c.chunk_length <= cut]
            assert got == want[: len(got)], f"cut at {cut}: not a prefix of the recording"
            assert len(got) >= _frames_in(complete, frames), f"cut at {cut}: lost frames before the damage"
            assert not r.indexed and r.warnings
            if got:
                assert r.frame_at(1e9)[1].to_dict() == got[-1]


@pytest.mark.parametrize("cut, message", [(0, "not an MCAP file"), (5, "not an MCAP file"),
                                          (12, "no header record"), (60, "")])
def test_cut_in_the_head_is_a_clear_error(tmp_path, clean, cut, message):
    path, _, _ = clean
    p = tmp_path / "head.mcap"
    p.write_bytes(path.read_bytes()[:cut])
    with pytest.raises(RecordingError, match=message or "damaged"):
        open_recording(p)


@pytest.mark.parametrize("summary", [True, False])
def test_a_corrupted_chunk_is_skipped_and_the_rest_plays(tmp_path, clean, summary):
    path, frames, chunks = clean
    data = bytearray(path.read_bytes())
    k = len(chunks) // 2
    c = chunks[k]
    mid = c.chunk_start_offset + c.chunk_length // 2
    data[mid:mid + 16] = bytes(16)  # zeroes inside the compressed payload
    if not summary:
        summary_start = int.from_bytes(data[len(data) - 8 - 20: len(data) - 8 - 12], "little")
        data = data[: summary_start - 13]
    p = tmp_path / "corrupt.mcap"
    p.write_bytes(bytes(data))
    with open_recording(p) as r:
        assert r.indexed == summary
        got = _dicts(r)
        assert r.damaged and any(str(c.chunk_start_offset) in w for w in r.warnings)
        lost = _frames_in(chunks[: k + 1], frames) - _frames_in(chunks[:k], frames)
        assert lost > 0
        kept = [as_recorded(f).to_dict() for f in frames]
        before = _frames_in(chunks[:k], frames)
        assert got == kept[:before] + kept[before + lost:]


def test_a_broken_record_length_stops_the_scan_there(tmp_path, clean):
    path, frames, chunks = clean
    data = bytearray(path.read_bytes())
    summary_start = int.from_bytes(data[len(data) - 8 - 20: len(data) - 8 - 12], "little")
    data = data[: summary_start - 13]
    k = len(chunks) // 3
    off = chunks[k].chunk_start_offset
    data[off + 1: off + 9] = (2**40).to_bytes(8, "little")
    p = tmp_path / "len.mcap"
    p.write_bytes(bytes(data))
    with open_recording(p) as r:
        got = _dicts(r)
        assert got == [as_recorded(f).to_dict() for f in frames[: _frames_in(chunks[:k], frames)]]
        assert any(f"byte {off}" in w for w in r.warnings)


def _mcap(path, profile, metadata, messages=()):
    with open(path, "wb") as fh:
        w = Writer(fh)
        w.start(profile=profile, library="test")
        if metadata is not None:
            w.add_metadata("swarmdeck", {k: json.dumps(v) for k, v in metadata.items()})
        sid = w.register_schema("swarmdeck.Frame", "jsonschema", b"{}")
        ch = w.register_channel("/swarmdeck/frame", "json", sid)
        for i, payload in enumerate(messages):
            w.add_message(ch, log_time=1000 + i, data=payload, publish_time=1000 + i)
        w.finish()


def test_foreign_and_newer_files_are_refused_clearly(tmp_path):
    cases = [
        ("ros.mcap", "ros2", {"recording_format": 1}, "another tool .*ros2"),
        ("nometa.mcap", "swarmdeck", None, "no 'swarmdeck' metadata"),
        ("newer.mcap", "swarmdeck", {"recording_format": 4, "frame_format": 1}, "format 4 by a newer swarmdeck"),
        ("newframe.mcap", "swarmdeck", {"recording_format": 1, "frame_format": 7}, "frames in format 7"),
    ]
    for name, profile, meta, msg in cases:
        _mcap(tmp_path / name, profile, meta)
        with pytest.raises(RecordingError, match=msg):
            open_recording(tmp_path / name)
    (tmp_path / "notes.txt").write_text("hello, this is not a recording\n")
    with pytest.raises(RecordingError, match="not an MCAP file"):
        open_recording(tmp_path / "notes.txt")
    with pytest.raises(RecordingError, match="is a folder"):
        open_recording(tmp_path)
    with pytest.raises(RecordingError, match="no such file"):
        open_recording(tmp_path / "missing.mcap")


def test_undecodable_frames_are_skipped_with_a_warning(tmp_path):
    good = [json.dumps(f.to_dict()).encode() for f in simulated_frames(n_robots=3, n_ticks=2, coverage=False)]
    bad = [b"{not json", json.dumps({"format": 1, "tick": 1}).encode()]
    _mcap(tmp_path / "mixed.mcap", "swarmdeck", {"recording_format": 1, "frame_format": 1},
          [good[0], bad[0], bad[1], good[1]])
    with open_recording(tmp_path / "mixed.mcap") as r:
        assert [f.tick for _, f in r.frames()] == [0, 1]
        assert sum("undecodable frame" in w for w in r.warnings) == 2


def test_a_garbled_summary_falls_back_to_scanning(tmp_path, clean):
    path, frames, _ = clean
    data = bytearray(path.read_bytes())
    summary_start = int.from_bytes(data[len(data) - 28: len(data) - 20], "little")
    data[summary_start: len(data) - 37] = bytes(len(data) - 37 - summary_start)
    p = tmp_path / "garbled.mcap"
    p.write_bytes(bytes(data))
    with open_recording(p) as r:
        assert not r.indexed and r.warnings
        assert _dicts(r) == [as_recorded(f).to_dict() for f in frames]
