"""The sandbox pipe protocol: frames round-trip, and anything else is a ProtocolError (never another exception)."""
import os

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from swarmdeck.console.jobs.protocol import MAX_FRAME, FrameReader, ProtocolError, decode, encode, floats, pack, write_frame


def test_frames_round_trip_through_a_real_pipe_in_pieces():
    r, w = os.pipe()
    poses = np.random.default_rng(0).normal(size=(7, 3))
    write_frame(w, {"t": "poses", "k": 3, "time": 0.099, "poses": pack(poses)})
    write_frame(w, {"t": "end", "reason": "over"})
    os.close(w)
    reader = FrameReader(r)
    first = reader.read_blocking()
    assert first["k"] == 3 and first["time"] == 0.099
    np.testing.assert_array_equal(floats(first, "poses", (7, 3)), poses)
    assert reader.read_blocking() == {"t": "end", "reason": "over"}
    with pytest.raises(EOFError):
        reader.read_blocking()
    os.close(r)


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=64))
def test_garbage_bodies_are_protocol_errors(body):
    try:
        message = decode(body)
    except ProtocolError:
        return
    assert isinstance(message, dict) and isinstance(message["t"], str)


@pytest.mark.parametrize("value", [b"\0" * 7, "text", None, 3, b"\0" * 16])
def test_arrays_of_the_wrong_size_or_type_are_protocol_errors(value):
    with pytest.raises(ProtocolError):
        floats({"t": "cmd", "v": value}, "v", (3,))


def test_an_oversized_frame_header_is_refused_before_reading_it():
    r, w = os.pipe()
    os.write(w, (MAX_FRAME + 1).to_bytes(4, "little") + b"xx")
    reader = FrameReader(r)
    reader.feed()
    with pytest.raises(ProtocolError, match="exceeds the limit"):
        reader.next()
    os.close(r)
    os.close(w)
    assert decode(encode({"t": "ready"})[4:]) == {"t": "ready"}
