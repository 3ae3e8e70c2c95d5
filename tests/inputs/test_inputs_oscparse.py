"""parse_datagram: whole-datagram parsing with python-osc, structural rejection."""
from __future__ import annotations

import struct

import pytest

from swarmdeck.inputs import MalformedDatagram, parse_datagram
from swarmdeck.inputs import oscbuild as ob


def test_bundle_messages_in_order_with_nested_bundles_flattened():
    inner = ob.bundle(ob.message("/b", "i", 2), at=1.9e9)
    d = ob.bundle(ob.message("/a", "sf", "x", 0.5), inner, ob.message("/c", "TFN"))
    p = parse_datagram(d)
    assert [(a, v) for a, v in p.messages] == [("/a", ["x", 0.5]), ("/b", [2]), ("/c", [True, False, None])]
    assert p.timetag == pytest.approx(1.9e9, abs=1e-6)


def test_single_message_and_immediate_bundle_have_no_timetag():
    assert parse_datagram(ob.message("/x", "i", 1)).timetag is None
    assert parse_datagram(ob.bundle(ob.message("/x", "i", 1))).timetag is None


def test_message_without_type_tag_string_is_legal_osc_1_0():
    assert parse_datagram(b"/ab\x00").messages == [("/ab", [])]


@pytest.mark.parametrize("data, reason, words", [
    (b"", "empty", "empty"),
    (b"/ab\x00\x00", "unaligned", "multiple of 4"),
    (b"\x00\x01\x02\x03", "not_osc", "neither"),
    (b"#bundle\x00\x00\x00", "unaligned", "multiple of 4"),
    (b"#bundle\x00" + bytes(8) + struct.pack(">i", -4) + b"/ab\x00", "bad_bundle", "positive multiple of 4"),
    (b"#bundle\x00" + bytes(8) + struct.pack(">i", 400) + b"/ab\x00", "bad_bundle", "within"),
    (b"#bundle\x00" + bytes(8) + struct.pack(">i", 4) + b"xyz\x00", "bad_message", "neither"),
    (b"/a\x00\x00,c\x00\x00\x00\x00\x00A", "unknown_type", "'c'"),  # python-osc would mis-parse
    (b"/a\x00\x00,i\x00\x00", "parse_error", "too short"),  # int32 argument missing
    (b"/abc", "bad_message", "NUL"),
])
def test_malformed_datagrams_name_what_was_wrong(data, reason, words):
    with pytest.raises(MalformedDatagram) as exc:
        parse_datagram(data)
    assert exc.value.reason == reason
    assert words in str(exc.value)


def test_size_limit():
    big = ob.bundle(*[ob.message("/tuio/2Dcur", "sifffff", "set", i, 0.5, 0.5, 0.0, 0.0, 0.0) for i in range(300)])
    assert len(parse_datagram(big).messages) == 300
    with pytest.raises(MalformedDatagram, match="exceeds the 8192-byte limit"):
        parse_datagram(big, max_bytes=8192)


def test_deeply_nested_bundles_are_rejected():
    d = ob.message("/x", "")
    for _ in range(12):
        d = ob.bundle(d)
    with pytest.raises(MalformedDatagram, match="nested deeper"):
        parse_datagram(d)
