"""The pipe protocol between the trusted side and a sandboxed script (one exchange per tick).

Frames are a 4-byte little-endian length and a msgpack map (msgspec). Arrays
travel as raw little-endian float64 bytes with their shape implied by the
message (``poses``: N × 3, ``v``/``w``: N). The trusted side decodes everything
the child sends with :func:`decode` and :func:`floats`, which check sizes,
types and shapes, so a child that writes garbage gets a clear
:class:`ProtocolError`, never a crash of the parent.

Messages, parent → child:
    ``{"t": "start", ...}`` the run's settings (see :mod:`.child`);
    ``{"t": "poses", "k": tick, "time": s, "poses": bytes}`` the poses the script sees;
    ``{"t": "end", "reason": str}`` the run is over (the script's next step ends it).
Child → parent:
    ``{"t": "ready"}`` swarmdeck's side of the child is loaded and confined; the script starts now;
    ``{"t": "arena", "n": N, "initial": bytes | None, "duration": s | None}`` the script built its Arena;
    ``{"t": "cmd", "k": tick, "v": bytes, "w": bytes, "invalid": count}`` unicycle commands for the
    poses of tick k; ``invalid``: robot-steps whose NaN/inf commands the script's Arena stopped so far;
    ``{"t": "done", "error": str | None, "error_line": str | None, "cpu_s": s}`` the script finished
    (``cpu_s``: the child's own CPU time, as it reports it: informational only).
"""
from __future__ import annotations

import os
import struct
from typing import Any

import msgspec
import numpy as np
from numpy.typing import NDArray

MAX_FRAME = 1 << 20  # bytes; 50 robots' poses are 1.2 kB
_HEADER = struct.Struct("<I")
_encoder = msgspec.msgpack.Encoder()
_decoder = msgspec.msgpack.Decoder()


class ProtocolError(Exception):
    """The other side sent something that is not a valid frame or message."""


def encode(message: dict[str, Any]) -> bytes:
    """One frame: length header and msgpack body."""
    body = _encoder.encode(message)
    return _HEADER.pack(len(body)) + body


def decode(body: bytes) -> dict[str, Any]:
    """The message in a frame body; ProtocolError unless it is a map with a string ``t``."""
    try:
        message = _decoder.decode(body)
    except (msgspec.DecodeError, ValueError, RecursionError) as exc:  # UnicodeDecodeError is a ValueError
        raise ProtocolError(f"undecodable frame ({len(body)} bytes): {exc}") from exc
    if not isinstance(message, dict) or not isinstance(message.get("t"), str):
        raise ProtocolError(f"frame is not a message with a type: {str(message)[:80]!r}")
    return message


def pack(array: NDArray[np.float64]) -> bytes:
    """Array → little-endian float64 bytes."""
    return np.ascontiguousarray(array, dtype="<f8").tobytes()


def floats(message: dict[str, Any], key: str, shape: tuple[int, ...]) -> NDArray[np.float64]:
    """``message[key]`` as a float64 array of ``shape`` (a copy); ProtocolError otherwise."""
    raw = message.get(key)
    if not isinstance(raw, (bytes, bytearray)):
        raise ProtocolError(f"{message.get('t')!r} message: {key!r} must be bytes, got {type(raw).__name__}")
    expected = int(np.prod(shape)) * 8
    if len(raw) != expected:
        raise ProtocolError(f"{message.get('t')!r} message: {key!r} has {len(raw)} bytes, expected {expected} for shape {shape}")
    return np.frombuffer(raw, dtype="<f8").reshape(shape).astype(np.float64)


def write_frame(fd: int, message: dict[str, Any]) -> None:
    """Write one whole frame to a blocking file descriptor."""
    view = memoryview(encode(message))
    while view:
        written = os.write(fd, view)
        view = view[written:]


class FrameReader:
    """Reassembles frames from a file descriptor fed by :meth:`feed` (non-blocking use) or read blocking."""

    def __init__(self, fd: int) -> None:
        self.fd = fd
        self._buffer = bytearray()

    def feed(self) -> bool:
        """Read what is available (one os.read); False at end of file."""
        chunk = os.read(self.fd, 1 << 16)
        if not chunk:
            return False
        self._buffer += chunk
        return True

    def next(self) -> dict[str, Any] | None:
        """The next complete message, or None if the buffer holds no whole frame yet."""
        if len(self._buffer) < _HEADER.size:
            return None
        (length,) = _HEADER.unpack_from(self._buffer)
        if length > MAX_FRAME:
            raise ProtocolError(f"frame of {length} bytes exceeds the limit of {MAX_FRAME}")
        if len(self._buffer) < _HEADER.size + length:
            return None
        body = bytes(self._buffer[_HEADER.size : _HEADER.size + length])
        del self._buffer[: _HEADER.size + length]
        return decode(body)

    def read_blocking(self) -> dict[str, Any]:
        """The next message, blocking; EOFError when the other side closed the pipe."""
        while True:
            message = self.next()
            if message is not None:
                return message
            if not self.feed():
                raise EOFError("the other side closed the pipe")
