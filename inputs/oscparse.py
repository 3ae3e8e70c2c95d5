"""Parse one OSC datagram whole with python-osc's ``OscBundle``/``OscMessage``.

No Dispatcher and no python-osc server are involved (REFERENCE.md §6, notes/tuio.md §4):
bundle timetags are reported, never waited for; datagrams of any size up to the
configured limit are parsed (the socketserver servers silently drop > 8192 bytes);
nested bundles are flattened in their original order.

Before python-osc sees the bytes, a cheap structural walk rejects what python-osc
would mis-handle: bundle element sizes that are negative, unaligned or overrun
the datagram (python-osc can loop forever on a negative size) and type tags it
does not know (it logs and silently mis-parses the remaining arguments).
"""
from __future__ import annotations

import struct
from dataclasses import dataclass

from pythonosc import osc_bundle, osc_message
from pythonosc.parsing import osc_types

from swarmdeck.core.errors import SwarmdeckError

BUNDLE_PREFIX = b"#bundle\x00"
#: Type tags python-osc can parse (``osc_message.OscMessage``).
KNOWN_TAGS = b"ifsdbhrmtTFN[]"
_INT = struct.Struct(">i")
_MAX_DEPTH = 8


class MalformedDatagram(ValueError, SwarmdeckError):
    """A datagram that is not valid OSC. ``reason`` is a short counter key
    (``empty``, ``too_large``, ``unaligned``, ``not_osc``, ``bad_bundle``,
    ``bad_message``, ``unknown_type``, ``too_many_arguments``, ``parse_error``);
    ``str(exc)`` explains it."""

    def __init__(self, reason: str, detail: str) -> None:
        super().__init__(f"{reason}: {detail}")
        self.reason = reason
        self.detail = detail


@dataclass(frozen=True, slots=True)
class ParsedDatagram:
    """``messages``: ``[(address, params), ...]`` in datagram order; ``timetag``:
    the latest bundle timetag in Unix seconds, ``None`` for unbundled messages and
    immediate bundles; ``cost``: messages + their type tags (the decode work)."""

    messages: list
    timetag: float | None
    cost: int = 0


def _check_message(data: bytes, start: int, end: int) -> int:
    """Structural check of one message ``data[start:end]``: address, then a type
    tag string of known tags (an absent type tag string is legal OSC 1.0).
    Returns its decode cost: 1 + the number of type tags."""
    if data[start:start + 1] != b"/":
        raise MalformedDatagram("bad_message", f"element at byte {start} does not start with '/' (got {data[start:start + 8]!r})")
    nul = data.find(b"\x00", start, end)
    if nul < 0:
        raise MalformedDatagram("bad_message", f"address at byte {start} is not NUL-terminated")
    tag_start = start + ((nul - start) // 4 + 1) * 4
    if tag_start >= end:
        return 1
    if data[tag_start:tag_start + 1] != b",":
        raise MalformedDatagram("bad_message", f"type tag string at byte {tag_start} does not start with ','")
    tag_end = data.find(b"\x00", tag_start, end)
    if tag_end < 0:
        raise MalformedDatagram("bad_message", f"type tag string at byte {tag_start} is not NUL-terminated")
    bad = data[tag_start + 1:tag_end].translate(None, KNOWN_TAGS)
    if bad:
        raise MalformedDatagram("unknown_type", f"unsupported OSC type tag(s) {bad.decode('latin-1')!r}; supported: {KNOWN_TAGS.decode()}")
    return tag_end - tag_start


def _check_bundle(data: bytes, start: int, end: int, depth: int) -> int:
    """Walk a bundle's element sizes (each > 0, a multiple of 4 and within the
    bundle) and check each message's address and type tags (inlined for speed).
    Returns the decode cost of its messages (1 + type tags each)."""
    if depth > _MAX_DEPTH:
        raise MalformedDatagram("bad_bundle", f"bundles nested deeper than {_MAX_DEPTH}")
    i = start + 16
    if i > end:
        raise MalformedDatagram("bad_bundle", f"bundle at byte {start} is shorter than its 16-byte header")
    unpack = _INT.unpack_from
    find = data.find
    cost = 0
    while i < end:
        if i + 4 > end:
            raise MalformedDatagram("bad_bundle", f"element size at byte {i} is truncated")
        (size,) = unpack(data, i)
        i += 4
        stop = i + size
        if size <= 0 or size & 3 or stop > end:
            raise MalformedDatagram("bad_bundle", f"element size {size} at byte {i - 4} must be a positive multiple of 4 within the {end - i} bytes left")
        first = data[i]
        if first == 47:  # "/": a message; "," cannot occur in an OSC address
            comma = find(b",", i, stop)
            if comma >= 0:
                nul = find(b"\x00", comma, stop)
                if nul < 0 or data[comma - 1] != 0 or data[comma + 1:nul].translate(None, KNOWN_TAGS):
                    cost += _check_message(data, i, stop)  # slow path: precise error
                else:
                    cost += nul - comma
            else:
                cost += _check_message(data, i, stop)
        elif data.startswith(BUNDLE_PREFIX, i):
            cost += _check_bundle(data, i, stop, depth + 1)
        else:
            raise MalformedDatagram("bad_message", f"element at byte {i} is neither a message ('/') nor a bundle (got {data[i:i + 8]!r})")
        i = stop
    return cost


def _direct_fields_work() -> bool:
    """python-osc 1.10 keeps a message's address and argument list in
    ``_address_regexp`` / ``_parameters``; reading them directly (no property
    call, no list copy) is ~10 % of the parse time of a 10-finger bundle. Verified
    once at import against the public ``address``/``params``; else use those."""
    try:
        m = osc_message.OscMessage(b"/a\x00\x00,if\x00\x00\x00\x00\x00\x07?\x80\x00\x00")
        return m._address_regexp == m.address == "/a" and m._parameters == m.params == [7, 1.0]
    except Exception:  # pragma: no cover - other python-osc internals
        return False


_DIRECT = _direct_fields_work()
_Message = osc_message.OscMessage


def _flatten(bundle: osc_bundle.OscBundle, out: list, stamps: list) -> None:
    ts = bundle.timestamp
    if ts:  # 0 == IMMEDIATELY
        stamps.append(ts)
    for item in bundle:
        if type(item) is _Message:
            if _DIRECT:
                out.append((item._address_regexp, item._parameters))
            else:  # pragma: no cover
                out.append((item.address, item.params))
        else:
            _flatten(item, out, stamps)


def _check_cost(cost: int, max_arguments: int | None) -> None:
    if max_arguments is not None and cost > max_arguments:
        raise MalformedDatagram("too_many_arguments",
                                f"datagram holds {cost} OSC messages and arguments, more than the limit of "
                                f"{max_arguments} per datagram (max_osc_arguments); not decoded")


def parse_datagram(data: bytes, max_bytes: int = 65536, max_arguments: int | None = None) -> ParsedDatagram:
    """Parse a whole OSC datagram (bundle or single message). ``max_arguments``
    bounds the decode work: a datagram whose messages + type tags exceed it is
    rejected by the structural walk, before python-osc decodes anything.

    Raises:
        MalformedDatagram: with a reason key and a message naming what was wrong.
    """
    n = len(data)
    if n == 0:
        raise MalformedDatagram("empty", "empty datagram")
    if n > max_bytes:
        raise MalformedDatagram("too_large", f"datagram of {n} bytes exceeds the {max_bytes}-byte limit")
    if n % 4:
        raise MalformedDatagram("unaligned", f"datagram length {n} is not a multiple of 4 (OSC packets are 4-byte aligned)")
    try:
        if data.startswith(BUNDLE_PREFIX):
            cost = _check_bundle(data, 0, n, 0)
            _check_cost(cost, max_arguments)
            out: list = []
            stamps: list = []
            _flatten(osc_bundle.OscBundle(data), out, stamps)
            return ParsedDatagram(out, max(stamps) if stamps else None, cost)
        if data[:1] == b"/":
            cost = _check_message(data, 0, n)
            _check_cost(cost, max_arguments)
            m = osc_message.OscMessage(data)
            return ParsedDatagram([(m.address, m.params)], None, cost)
    except MalformedDatagram:
        raise
    except (osc_bundle.ParseError, osc_message.ParseError, osc_types.ParseError) as exc:
        raise MalformedDatagram("parse_error", f"python-osc could not parse it: {exc}") from None
    except Exception as exc:  # python-osc raises assorted errors on hostile bytes
        raise MalformedDatagram("parse_error", f"{type(exc).__name__}: {exc}") from None
    raise MalformedDatagram("not_osc", f"datagram starts with {data[:8]!r}, neither '#bundle' nor '/'")
