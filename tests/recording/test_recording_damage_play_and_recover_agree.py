"""``swarmdeck play`` and ``swarmdeck recover`` walk a damaged file the same way: what the reader plays
is exactly what ``recover`` writes, for every kind of damage, with the file's summary and without.

Both go through one damage-tolerant MCAP walker (``console/recording/mcap_walk.py``): a record whose
head is damaged (an opcode that is no MCAP record, zeroed bytes) or whose length runs past the end
ends the walk there — unless the file's summary indexes a chunk after it, where the walk resumes;
a chunk that fails its CRC is skipped and the next one read.
"""
from __future__ import annotations

import pytest
from mcap.reader import make_reader
from recording_synth import simulated_frames

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
from swarmdeck.console.recording.recover import recover


@pytest.fixture(scope="module")
def clean(tmp_path_factory):
    path = tmp_path_factory.mktemp("agree") / "clean.mcap"
    with Recorder(path, config=RecorderConfig(chunk_size=2500, foxglove=False)) as rec:
        for f in simulated_frames(n_robots=5, n_ticks=120, seed=9, coverage=False):
            rec.write_frame(f)
    with open(path, "rb") as fh:
        chunks = sorted(make_reader(fh).get_summary().chunk_indexes, key=lambda c: c.chunk_start_offset)
    assert len(chunks) >= 6
    return path.read_bytes(), [(c.chunk_start_offset, c.chunk_length) for c in chunks]


def _without_summary(data: bytes) -> bytes:
    """The file as a crash leaves it: everything before the data-end record (13 bytes before the summary)."""
    summary_start = int.from_bytes(data[len(data) - 28: len(data) - 20], "little")
    return data[: summary_start - 13]


def _zero(data: bytearray, at: int, n: int) -> None:
    data[at: at + n] = bytes(n)


def _set(data: bytearray, at: int, value: bytes) -> None:
    data[at: at + len(value)] = value


DAMAGE = {  # name -> damage(data, offset of the chunk record, its length)
    "unknown opcode": lambda d, off, n: _set(d, off, b"\x55"),
    "zeroed record head": lambda d, off, n: _zero(d, off, 9),
    "length past the end": lambda d, off, n: _set(d, off + 1, (2**40).to_bytes(8, "little")),
    "bad chunk CRC": lambda d, off, n: _zero(d, off + n // 2, 16),
    "zeroed chunk tail": lambda d, off, n: _zero(d, off + n - 40, 40),
}


def _frames(path):
    with open_recording(path) as r:
        frames = [(f.tick, f.poses.tobytes(), f.v.tobytes()) for _, f in r.frames()]
        events = [(e.kind, e.text) for e in r.events()]
        return frames, events, list(r.warnings), r.indexed


@pytest.mark.parametrize("summary", [True, False], ids=["with summary", "cut off"])
@pytest.mark.parametrize("damage", list(DAMAGE))
def test_recover_writes_exactly_what_the_reader_plays(tmp_path, clean, damage, summary):
    data, chunks = clean
    hurt = DAMAGE[damage]
    raw = bytearray(data if summary else _without_summary(data))
    off, length = chunks[len(chunks) // 2]
    hurt(raw, off, length)
    src = tmp_path / "damaged.mcap"
    src.write_bytes(bytes(raw))

    played, events, warnings, _ = _frames(src)
    assert played and warnings, "the damage is seen and something before it plays"
    report = recover(src, tmp_path / "recovered.mcap")
    back, back_events, back_warnings, indexed = _frames(report.output)
    assert indexed and not back_warnings
    assert [f[0] for f in back] == [f[0] for f in played]
    assert back == played and back_events == events
    assert report.chunks + report.skipped_chunks <= len(chunks)
    if summary:  # the summary indexes the chunks after the damage: both read on there
        assert played[-1][0] == 119


def test_the_walk_stops_at_a_cut_the_same_way(tmp_path, clean):
    data, chunks = clean
    base = _without_summary(data)
    for off, length in chunks[1::2]:
        for cut in (off, off + 5, off + length // 2):
            src = tmp_path / f"cut{cut}.mcap"
            src.write_bytes(base[:cut])
            played = _frames(src)[0]
            report = recover(src, tmp_path / f"cut{cut}.recovered.mcap")
            assert _frames(report.output)[0] == played
            assert "cut off" in report.stopped and report.stopped_at == off
