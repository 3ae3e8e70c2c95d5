"""The pipe protocol between the trusted side and a sandboxed script (one exchange per tick).

A frame is a 4-byte little-endian length, a kind byte and a body. The two
frames of every tick are fixed binary layouts — no encoder, one ``os.write``
each, the arrays as raw little-endian float64:

* ``P`` poses, parent → child: tick ``k`` (int64), time (float64, s), poses N × 3;
* ``C`` commands, child → parent: tick ``k`` (int64), the nominal single-integrator
  velocities of the look-ahead points N × 2 (m/s; the trusted side certifies them:
  wheel limits, barrier, NaN/inf rows stopped and counted).

Everything else (once a run) is a ``M`` frame holding a msgpack map (msgspec).
The trusted side decodes everything the child sends with :meth:`FrameReader.next`,
:func:`commands`, :func:`decode` and :func:`floats`, which check sizes, kinds,
types and shapes, so a child that writes garbage gets a clear
:class:`ProtocolError`, never a crash of the parent.

Messages, parent → child:
    ``{"t": "start", ...}`` the run's settings (see :mod:`.child`);
    ``P`` frames: the poses the script sees;
    ``{"t": "end", "reason": str}`` the run is over (the script's next step ends it);
    ``{"t": "readings", ...}`` before a ``P`` frame: what the robots sensed (:mod:`.senses`), when the script has sensors;
    ``{"t": "inboxes", ...}`` before a ``P`` frame, and once in answer to ``decentralised``: the trusted network's
    deliveries (:mod:`.network_link`).
Child → parent:
    ``{"t": "ready"}`` swarmdeck's side of the child is loaded and confined; the script starts now;
    ``{"t": "arena", "n": N, "initial": bytes | None[, "m": M, "obstacles": bytes]}`` the script built its Arena
    (``obstacles``: the M × 2 × 2 segments it declared, m — made solid on the trusted side, :func:`obstacles`);
    ``{"t": "draw", "kinds", "offsets", "vertices", "sizes", "colors", "filled": bytes, "texts": [str]}``
    what the script draws from its next ``C`` frame on (sent before it, only when the drawing changed;
    :func:`encode_annotations` / :func:`decode_draw`: the arrays as raw little-endian bytes, vertices and
    sizes float32), checked and capped on the trusted side;
    ``C`` frames: commands for the poses of tick k (one per ``P`` frame; a ``k`` other than the last ``P``
    frame's is a missed tick for the trusted side: robots stopped, simulated time goes on);
    ``{"t": "network", "k": k, "links": bytes, "rate": bytes}`` before the ``C`` frame of tick k of a decentralised
    run (``swarmdeck.devices.decentralised``): its network's last links E × 2 (float64 robot indices) and messages
    per second over each (E,) — the script's own account, shown and recorded, never trusted for anything else;
    ``{"t": "metrics", "k": k, "values": {name: float}}`` before the ``C`` frame of tick k, at most once per tick and
    only when they changed: what the script recorded with ``swarmdeck.devices.record_metrics`` (checked by
    ``check_metrics``: its own account, for a sweep's table);
    ``{"t": "sensors", "config": {...} | None}``, ``{"t": "leds", "rgb": bytes}`` the script's sensors and LEDs
    (:mod:`.senses`: the readings are computed on the trusted side);
    ``{"t": "decentralised", ...}`` once, ``{"t": "outbox", "k", "messages"}`` before tick k's ``C`` frame: a
    decentralised run's network configuration and its robots' messages (:mod:`.network_link`: the network lives on
    the trusted side);
    ``{"t": "done", "error": str | None, "error_line": str | None, "cpu_s": s, "metrics": {...}}`` the script finished
    (``cpu_s``: the child's own CPU time, as it reports it: informational only; ``metrics``: the last ones).
"""
from __future__ import annotations

import os
import struct
from typing import Any

import msgspec
import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.annotations import Annotations
from swarmdeck.core.errors import SwarmdeckError

MAX_FRAME = 1 << 20  # bytes; 50 robots' poses are 1.2 kB
_HEADER = struct.Struct("<I")
_POSES = struct.Struct("<Icqd")  # length, kind, k, time
_COMMANDS = struct.Struct("<Icq")  # length, kind, k
_encoder = msgspec.msgpack.Encoder()
_decoder = msgspec.msgpack.Decoder()
MESSAGE, POSES, COMMANDS = b"M", b"P", b"C"


class ProtocolError(SwarmdeckError):
    """The other side sent something that is not a valid frame or message."""


def encode(message: dict[str, Any]) -> bytes:
    """One ``M`` frame: length header, kind and msgpack body."""
    body = _encoder.encode(message)
    return _HEADER.pack(len(body) + 1) + MESSAGE + body


def encode_poses(k: int, time: float, poses: NDArray[np.float64]) -> bytes:
    """One ``P`` frame: tick ``k``, ``time`` s, ``poses`` (N, 3)."""
    data = np.ascontiguousarray(poses, dtype="<f8").tobytes()
    return _POSES.pack(len(data) + 17, POSES, k, time) + data


def encode_commands(k: int, nominal: NDArray[np.float64]) -> bytes:
    """One ``C`` frame: tick ``k``, nominal look-ahead velocities (N, 2)."""
    data = np.ascontiguousarray(nominal, dtype="<f8").tobytes()
    return _COMMANDS.pack(len(data) + 9, COMMANDS, k) + data


def decode(body: bytes) -> dict[str, Any]:
    """The message in an ``M`` frame's body; ProtocolError unless it is a map with a string ``t``."""
    try:
        message = _decoder.decode(body)
    except (msgspec.DecodeError, ValueError, RecursionError) as exc:  # UnicodeDecodeError is a ValueError
        raise ProtocolError(f"undecodable frame ({len(body)} bytes): {exc}") from exc
    if not isinstance(message, dict) or not isinstance(message.get("t"), str):
        raise ProtocolError(f"frame is not a message with a type: {str(message)[:80]!r}")
    return message


def poses(body: bytes, n: int) -> tuple[int, float, NDArray[np.float64]]:
    """(k, time, poses (n, 3)) of a ``P`` body; ProtocolError on a wrong size."""
    if len(body) != 16 + 24 * n:
        raise ProtocolError(f"poses frame of {len(body)} bytes, expected {16 + 24 * n} for {n} robots")
    k, time = struct.unpack_from("<qd", body)
    return k, time, np.frombuffer(body, dtype="<f8", offset=16).reshape(n, 3).astype(np.float64)


def commands(body: bytes, n: int) -> tuple[int, NDArray[np.float64]]:
    """(k, nominal (n, 2)) of a ``C`` body; ProtocolError on a wrong size."""
    if len(body) != 8 + 16 * n:
        raise ProtocolError(f"commands frame of {len(body)} bytes, expected {8 + 16 * n} for {n} robots")
    (k,) = struct.unpack_from("<q", body)
    return k, np.frombuffer(body, dtype="<f8", offset=8).reshape(n, 2).astype(np.float64)


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


#: most links a ``network`` message may carry (a complete graph of 141 robots)
MAX_NETWORK_LINKS = 20_000


def network_traffic(message: dict[str, Any], n: int) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """(links (E, 2) int, rate (E,) messages/s) of a ``network`` message for ``n`` robots; ProtocolError unless the
    links are whole robot indices 0..n−1 (at most :data:`MAX_NETWORK_LINKS`) and the rates finite and >= 0."""
    raw = message.get("links")
    if not isinstance(raw, (bytes, bytearray)) or len(raw) % 16 or len(raw) // 16 > MAX_NETWORK_LINKS:
        raise ProtocolError(f"'network' message: 'links' must be the bytes of at most {MAX_NETWORK_LINKS} float64 pairs")
    e = len(raw) // 16
    links = floats(message, "links", (e, 2))
    rate = floats(message, "rate", (e,))
    if not (np.all(np.isfinite(links)) and np.all(links == np.round(links)) and (links >= 0).all() and (links < n).all()):
        raise ProtocolError(f"'network' message: links must be robot indices 0..{n - 1}")
    if not (np.all(np.isfinite(rate)) and (rate >= 0).all()):
        raise ProtocolError("'network' message: rates must be finite and >= 0 messages/s")
    return links.astype(np.int64), rate


#: the bytes of a ``draw`` message the child sends at most (its arrays and texts; the frame cap is MAX_FRAME)
MAX_DRAW_BYTES = MAX_FRAME - (64 << 10)


def encode_annotations(ann: Annotations) -> dict[str, Any]:
    """The ``draw`` message of ``ann``; primitives past :data:`MAX_DRAW_BYTES` are left out (the child's
    side of the caps: the trusted side caps again)."""
    counts = ann.vertex_counts()
    cost = np.cumsum(counts * 8 + 15 + np.fromiter((len(t.encode("utf-8", "replace")) for t in ann.texts),
                                                    dtype=np.int64, count=len(ann)))
    if len(ann) and cost[-1] > MAX_DRAW_BYTES:
        ann = ann.select(cost <= MAX_DRAW_BYTES)
    return {"t": "draw", "kinds": ann.kinds.astype("|u1").tobytes(), "offsets": ann.offsets.astype("<i4").tobytes(),
            "vertices": ann.vertices.astype("<f4").tobytes(), "sizes": ann.sizes.astype("<f4").tobytes(),
            "colors": ann.colors.astype("|u1").tobytes(), "filled": ann.filled.astype("|u1").tobytes(),
            "texts": list(ann.texts)}


def decode_draw(message: dict[str, Any]) -> Annotations:
    """The :class:`~swarmdeck.core.annotations.Annotations` of a ``draw`` message, structure checked (the
    values are capped by :func:`~swarmdeck.core.annotations.sanitize`); ProtocolError naming what is wrong."""
    raw = {}
    for key in ("kinds", "offsets", "vertices", "sizes", "colors", "filled"):
        value = message.get(key)
        if not isinstance(value, (bytes, bytearray)):
            raise ProtocolError(f"'draw' message: {key!r} must be bytes, got {type(value).__name__}")
        raw[key] = bytes(value)
    texts = message.get("texts")
    if not isinstance(texts, list) or not all(isinstance(t, str) for t in texts):
        raise ProtocolError("'draw' message: 'texts' must be a list of strings")
    arrays = {}
    for key, dtype, width in (("kinds", "|u1", 1), ("offsets", "<i4", 1), ("vertices", "<f4", 2), ("sizes", "<f4", 1),
                              ("colors", "|u1", 4), ("filled", "|u1", 1)):
        item = np.dtype(dtype).itemsize * width
        if len(raw[key]) % item:
            raise ProtocolError(f"'draw' message: {key!r} has {len(raw[key])} bytes, not a multiple of {item}")
        arrays[key] = np.frombuffer(raw[key], dtype).reshape(-1, width) if width > 1 else np.frombuffer(raw[key], dtype)
    try:
        return Annotations(kinds=arrays["kinds"], offsets=arrays["offsets"].astype(np.int64),
                           vertices=arrays["vertices"].astype(np.float64), sizes=arrays["sizes"].astype(np.float64),
                           colors=arrays["colors"], filled=arrays["filled"].astype(bool), texts=tuple(texts))
    except ValueError as exc:  # shapes and offsets that disagree
        raise ProtocolError(f"'draw' message: {exc}") from None


MAX_OBSTACLES = 4096  # segments a script may declare


def obstacles(message: dict[str, Any]) -> NDArray[np.float64] | None:
    """The ``(M, 2, 2)`` segments (m) of an ``arena`` message, None when it declares none; ProtocolError when
    ``m`` and the bytes disagree or M is out of 1..MAX_OBSTACLES (the segments themselves are checked by
    :class:`~swarmdeck.core.obstacles.Obstacles` where they are used)."""
    if message.get("obstacles") is None:
        return None
    m = message.get("m")
    if not isinstance(m, int) or not 1 <= m <= MAX_OBSTACLES:
        raise ProtocolError(f"'arena' message: m (the number of obstacle segments) must be an integer in "
                            f"1..{MAX_OBSTACLES}, got {m!r}")
    return floats(message, "obstacles", (m, 2, 2))


def write_frame(fd: int, frame: bytes | dict[str, Any]) -> None:
    """Write one whole frame (encoded bytes, or a message to encode) to a blocking file descriptor."""
    view = memoryview(frame if isinstance(frame, bytes) else encode(frame))
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

    def next(self) -> tuple[bytes, bytes] | None:
        """(kind, body) of the next complete frame, or None if the buffer holds no whole frame yet."""
        buffer = self._buffer
        if len(buffer) < 5:
            return None
        (length,) = _HEADER.unpack_from(buffer)
        if length > MAX_FRAME or length < 1:
            raise ProtocolError(f"frame of {length} bytes is outside 1..{MAX_FRAME}")
        end = 4 + length
        if len(buffer) < end:
            return None
        kind, body = bytes(buffer[4:5]), bytes(buffer[5:end])
        del buffer[:end]
        if kind not in (MESSAGE, POSES, COMMANDS):
            raise ProtocolError(f"unknown frame kind {kind!r}")
        return kind, body

    def read_blocking(self) -> tuple[bytes, bytes]:
        """The next frame, blocking; EOFError when the other side closed the pipe."""
        while True:
            frame = self.next()
            if frame is not None:
                return frame
            if not self.feed():
                raise EOFError("the other side closed the pipe")
