"""The sandbox pipe protocol: binary tick frames and messages round-trip, and anything else is a
ProtocolError (never another exception)."""
import os

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.console.sandbox.protocol import (
    COMMANDS,
    MAX_FRAME,
    MESSAGE,
    POSES,
    FrameReader,
    ProtocolError,
    commands,
    decode,
    encode,
    encode_commands,
    encode_poses,
    floats,
    poses,
    write_frame,
)


def test_frames_round_trip_through_a_real_pipe_in_pieces():
    r, w = os.pipe()
    rng = np.random.default_rng(0)
    p, u = rng.normal(size=(7, 3)), rng.normal(size=(7, 2))
    u[2] = np.nan  # the trusted side decides about NaN rows; the protocol carries them
    stream = encode_poses(3, 0.099, p) + encode({"t": "end", "reason": "over"}) + encode_commands(4, u)
    for k in range(0, len(stream), 5):  # written in pieces of 5 bytes
        write_frame(w, stream[k : k + 5])
    os.close(w)
    reader = FrameReader(r)
    kind, body = reader.read_blocking()
    assert kind == POSES
    k, t, got = poses(body, 7)
    assert (k, t) == (3, 0.099) and np.array_equal(got, p)
    kind, body = reader.read_blocking()
    assert kind == MESSAGE and decode(body) == {"t": "end", "reason": "over"}
    kind, body = reader.read_blocking()
    k, got = commands(body, 7)
    assert kind == COMMANDS and k == 4 and np.array_equal(got, u, equal_nan=True)
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


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=200), st.integers(1, 8))
def test_garbage_tick_frames_are_protocol_errors_or_the_right_shape(body, n):
    for parse, shape in ((commands, (n, 2)), (poses, (n, 3))):
        try:
            array = parse(body, n)[-1]
        except ProtocolError:
            continue
        assert array.shape == shape and array.dtype == np.float64


@pytest.mark.parametrize("value", [b"\0" * 7, "text", None, 3, b"\0" * 16])
def test_arrays_of_the_wrong_size_or_type_are_protocol_errors(value):
    with pytest.raises(ProtocolError):
        floats({"t": "arena", "initial": value}, "initial", (3,))


def test_a_commands_frame_for_another_robot_count_is_refused():
    body = encode_commands(0, np.zeros((3, 2)))[5:]
    with pytest.raises(ProtocolError, match="expected"):
        commands(body, 4)


@pytest.mark.parametrize("header", [(MAX_FRAME + 1).to_bytes(4, "little") + b"xx", (0).to_bytes(4, "little") + b"x"])
def test_an_oversized_or_empty_frame_header_is_refused_before_reading_it(header):
    r, w = os.pipe()
    os.write(w, header)
    reader = FrameReader(r)
    reader.feed()
    with pytest.raises(ProtocolError, match="outside"):
        reader.next()
    os.close(r)
    os.close(w)


def test_an_unknown_frame_kind_is_refused():
    r, w = os.pipe()
    os.write(w, (3).to_bytes(4, "little") + b"Zab")
    reader = FrameReader(r)
    reader.feed()
    with pytest.raises(ProtocolError, match="unknown frame kind"):
        reader.next()
    os.close(r)
    os.close(w)
