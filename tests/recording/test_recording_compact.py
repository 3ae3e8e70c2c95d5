"""Compact recordings (frame format 2): exact poses and commands, derived geometry, old files still open.

A real console loop (coverage, barrier, wheel limits) is recorded: what the reader returns has the
poses and the (v, ω) sent bit for bit, the safe command as ṗ = M(θ)[v, ω] of the command sent, the
nominal and the intervention to float16, and the coverage cells, edges, neighbours, centroids and
masses recomputed bit for bit. Recordings in format 1 still read, and equal what the
mcap package's own reader and ``Frame.from_dict`` make of the same messages. File size per minute at
N = 100 is asserted from the bytes written (no timing).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from swarmdeck.console.recording.codec import decode_frame, encode_frame, pack_array, unpack_array
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig

FORMAT1 = Path(__file__).resolve().parents[1] / "data" / "recording_format1.mcap"


def loop_frames(n: int, ticks: int, seed: int = 3) -> list[Frame]:
    loop = ControlLoop(LoopConfig(n_robots=n, seed=seed))
    try:
        return [loop.tick() for _ in range(ticks)]
    finally:
        loop.close()


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    frames = loop_frames(30, 40)
    path = tmp_path_factory.mktemp("compact") / "c.mcap"
    with Recorder(path) as rec:
        for f in frames:
            rec.write_frame(f)
    with open_recording(path) as r:
        got = [f for _, f in r.frames()]
    return frames, got


def test_poses_and_commands_exact_geometry_recomputed(recorded):
    frames, got = recorded
    assert len(got) == len(frames)
    acted = 0
    for f, g in zip(frames, got):
        assert np.array_equal(g.poses, f.poses) and np.array_equal(g.v, f.v) and np.array_equal(g.w, f.w)
        assert np.array_equal(g.ids, f.ids) and np.array_equal(g.seen, f.seen)
        changed = np.abs(f.nominal - f.safe).max(initial=0.0)  # float16 offsets from the safe command
        assert np.abs(g.nominal - f.nominal).max(initial=0.0) <= 1e-3 * changed + 1e-12
        assert np.abs(g.safe - f.safe).max() < 1e-12  # the filter's answer is the command sent
        fc, gc = f.coverage, g.coverage
        for name in ("edges", "neighbours", "cell_vertices", "cell_offsets", "centroids", "masses"):
            assert np.array_equal(getattr(gc, name), getattr(fc, name)), name
        assert gc.cost_H == fc.cost_H and gc.packing_warning == fc.packing_warning
        fb, gb = f.barrier, g.barrier
        assert np.array_equal(gb.active_pairs, fb.active_pairs)
        assert np.allclose(gb.active_h, fb.active_h, rtol=0, atol=1e-12)
        assert np.allclose(gb.intervention, fb.intervention, rtol=1e-3, atol=1e-7)
        assert (gb.ok, gb.status, gb.min_distance) == (fb.ok, fb.status, fb.min_distance)
        acted += len(fb.active_pairs) > 0 or not fb.nominal_was_safe
        assert g.density.to_dict() == f.density.to_dict() and g.params == f.params
    assert acted, "the barrier never acted: the test would not see its fields"


def test_format1_recordings_still_open():
    with open_recording(FORMAT1) as r:
        assert r.metadata["recording_format"] == 1 and r.metadata["frame_format"] == 1
        got = [f.to_dict() for _, f in r.frames()]
        assert len(got) == 30 and len(list(r.datagrams())) == 6
        assert [e.text for e in r.events() if e.kind == "operator"] == ["e-stop"]
    with open(FORMAT1, "rb") as fh:  # the mcap package's reader + Frame.from_dict: the same frames
        want = [Frame.from_dict(json.loads(m.data)).to_dict()
                for _, ch, m in make_reader(fh).iter_messages() if ch.topic == "/swarmdeck/frame"]
    assert got == want


def test_size_per_minute_at_100_robots(tmp_path):
    """Bytes per minute of recording at 30 Hz: the size a file grows by per frame (the header, schemas
    and summary are written once), measured between a 8-frame and a 32-frame recording. swarmdeck's
    own channels only: the optional Foxglove channels (``RecorderConfig.foxglove``) come on top."""
    frames = loop_frames(100, 32, seed=5)
    sizes = []
    for k in (8, 32):
        path = tmp_path / f"n100_{k}.mcap"
        with Recorder(path, config=RecorderConfig(foxglove=False)) as rec:
            for f in frames[:k]:
                rec.write_frame(f)
        sizes.append(path.stat().st_size)
    per_frame = (sizes[1] - sizes[0]) / 24
    mb_per_min = per_frame * 30 * 60 / 1e6
    assert mb_per_min <= 8.0, f"{mb_per_min:.2f} MB per minute at N = 100"
    old = sum(len(json.dumps(f.to_dict())) for f in frames[8:]) / 24
    assert per_frame < old / 10  # format 1 wrote this as uncompressed JSON (83 kB a frame at N = 100)


@pytest.mark.parametrize("bad, message", [
    ({"nd": "<f8", "shape": [2, 3], "b64": "AAAA"}, "bytes for shape"),
    ({"nd": ">f8", "shape": [1], "b64": "AAAAAAAAAAA="}, "unsupported dtype"),
    ({"nd": "<f8", "shape": [1], "b64": "not base64!"}, "bad binary array"),
    ([[0.0, 0.0, 0.0]], "binary array object"),
])
def test_malformed_arrays_name_the_field(recorded, bad, message):
    frames, _ = recorded
    msg = json.loads(encode_frame(frames[0]))
    msg["poses"] = bad
    with pytest.raises(ValueError, match=f"poses.*{message}|{message}"):
        decode_frame(json.dumps(msg).encode())


def test_binary_arrays_round_trip_bit_for_bit():
    rng = np.random.default_rng(0)
    for a, dt in ((rng.normal(size=(7, 3)), "<f8"), (rng.integers(-5, 9, (4, 2)), "<i4"),
                  (rng.random(5) > 0.5, "|b1"), (np.zeros((0, 2)), "<f8"), (np.array([np.nan, np.inf]), "<f8")):
        back = unpack_array(json.loads(json.dumps(pack_array(a, dt))), "x")
        assert back.shape == a.shape and np.array_equal(back.astype(a.dtype), a, equal_nan=True)
