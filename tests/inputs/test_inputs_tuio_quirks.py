"""Golden TUIO 1.1 bundles, one per real sender's quirk (notes/tuio.md §1.5, §3),
built with explicit OSC type tags."""
from __future__ import annotations

import struct
import time

import numpy as np
import pytest
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder

from swarmdeck.inputs import Calibration, InputSource, ListenerConfig
from swarmdeck.inputs import oscbuild as ob

PEER = ("10.0.0.2", 50000)


def _pyosc(address: str, typed_args: list[tuple[object, str]]) -> bytes:
    b = OscMessageBuilder(address=address)
    for v, t in typed_args:
        b.add_arg(v, t)
    return b.build().dgram


def _events(snap):
    return sorted((e.kind, e.id) for e in snap.events)


def _pos(snap):
    return {c.id: c.position for c in snap.contacts}


def test_encoder_matches_python_osc_builder_with_explicit_types():
    ours = ob.message("/tuio/2Dcur", "sifffff", "set", 5, 0.25, 0.75, 1.0, 0.0, 0.0)
    ref = _pyosc("/tuio/2Dcur", [("set", "s"), (5, "i"), (0.25, "f"), (0.75, "f"), (1.0, "f"), (0.0, "f"), (0.0, "f")])
    assert ours == ref
    bb = OscBundleBuilder(IMMEDIATELY)
    bb.add_content(OscMessageBuilder(address="/tuio/2Dcur").build())
    # python-osc builds an argument-less message with an empty ',' type tag string
    assert ob.bundle(ob.message("/tuio/2Dcur", "")) == bb.build().dgram


def test_reference_server_splits_a_frame_into_bundles_with_equal_fseq():
    """TUIO11_CPP TuioServer: a frame too big for one packet is sent as several
    bundles, each with the full ALIVE, a share of the SETs and the same FSEQ."""
    src = InputSource()
    ids = list(range(100, 125))
    pts = [(s, 0.02 + 0.038 * i, 0.5, 0.0, 0.0, 0.0) for i, s in enumerate(ids)]
    for k, chunk in enumerate((pts[:10], pts[10:20], pts[20:])):
        src.feed(ob.tuio_bundle("2Dcur", ids, chunk, fseq=7, source="TuioPad@10.0.0.2"), PEER, 0.01 * k)
    snap = src.poll(0.03)
    assert len(snap.contacts) == 25
    assert _events(snap) == [("down", s) for s in ids]
    x = Calibration().to_arena(np.array([[p[1], p[2]] for p in pts]))
    got = _pos(snap)
    np.testing.assert_allclose([got[s] for s in ids], x, atol=1e-6)
    (h,) = [h for h in snap.health if h.kind == "tuio"]
    assert h.warnings.get("late", 0) == 0 and not h.errors
    # next frame moves one finger with fseq 8 (only its SET, full ALIVE)
    src.feed(ob.tuio_bundle("2Dcur", ids, [(100, 0.9, 0.9, 0.0, 0.0, 0.0)], fseq=8, source="TuioPad@10.0.0.2"), PEER, 0.05)
    snap = src.poll(0.05)
    assert _events(snap) == [("move", 100)]
    assert len(snap.contacts) == 25


def test_reference_server_empty_bundle_removes_everything():
    src = InputSource()
    src.feed(ob.tuio_bundle("2Dcur", [1, 2], ob.cursor_sets([(1, 0.1, 0.1), (2, 0.9, 0.9)]), fseq=3, source="s@h"), PEER, 0.0)
    src.feed(ob.tuio_bundle("2Dcur", [], [], fseq=-1, source="s@h"), PEER, 0.1)
    snap = src.poll(0.1)
    assert snap.contacts == ()
    assert _events(snap) == [("down", 1), ("down", 2), ("up", 1), ("up", 2)]


def test_reactivision_objects_with_plain_source_string():
    """reacTIVision to localhost: source without '@', 2Dobj with fiducial class ids."""
    src = InputSource()
    sets = [(11, 4, 0.25, 0.25, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0), (12, 4, 0.75, 0.5, 2.0, 0.1, 0.0, 0.0, 0.0, 0.0)]
    src.feed(ob.tuio_bundle("2Dobj", [11, 12], sets, fseq=1, source="reacTIVision"), ("127.0.0.1", 3334), 0.0)
    snap = src.poll(0.0)
    assert {c.source for c in snap.contacts} == {"udp://127.0.0.1/reacTIVision"}
    assert {(c.id, c.kind, c.class_id) for c in snap.contacts} == {(11, "object", 4), (12, "object", 4)}
    c12 = [c for c in snap.contacts if c.id == 12][0]
    np.testing.assert_allclose(c12.velocity, [0.1 * 3.2, 0.0], atol=1e-6)  # X = 0.1 axis/s, y-down → arena


def _simulator_timetag_bundle(msgs: list[bytes]) -> bytes:
    # TUIO Simulator (Java, illposed OSC): wall-clock seconds, fraction computed as ms*1000
    now = time.time()
    sec = int(now + ob.NTP_DELTA)
    frac = int((now % 1.0) * 1000) * 1000
    return b"#bundle\x00" + struct.pack(">II", sec, frac) + b"".join(struct.pack(">i", len(m)) + m for m in msgs)


def test_tuio_simulator_once_a_second_refresh_with_fseq_minus_one():
    src = InputSource()
    ids = list(range(1, 13))
    pts = [(s, 0.05 + 0.07 * s, 0.4, 0.0, 0.0, 0.0) for s in ids]
    src.feed(_simulator_timetag_bundle(ob.tuio_messages("2Dcur", ids, pts, fseq=40, source="tsim@10.0.0.3")), PEER, 0.0)
    # a drag: only the moved cursor's SET, next frame number
    src.feed(_simulator_timetag_bundle(ob.tuio_messages("2Dcur", ids, [(5, 0.5, 0.8, 0.0, 0.0, 0.0)], fseq=41, source="tsim@10.0.0.3")), PEER, 0.2)
    # refresh: full state, at most 10 SETs per bundle, fseq -1 (never late though -1 < 41)
    src.feed(_simulator_timetag_bundle(ob.tuio_messages("2Dcur", ids, [(5, 0.5, 0.8, 0.0, 0.0, 0.0)] + [p for p in pts if p[0] != 5][:9], fseq=-1, source="tsim@10.0.0.3")), PEER, 1.0)
    src.feed(_simulator_timetag_bundle(ob.tuio_messages("2Dcur", ids, [p for p in pts if p[0] != 5][9:], fseq=-1, source="tsim@10.0.0.3")), PEER, 1.0)
    snap = src.poll(1.0)
    assert len(snap.contacts) == 12
    np.testing.assert_allclose(_pos(snap)[5], Calibration().to_arena(np.array([[0.5, 0.8]]))[0], atol=1e-6)
    # unchanged refresh SETs are not moves (5 moved; its finite-difference velocity then decays)
    assert {e.id for e in snap.events if e.kind == "move"} == {5}
    (h,) = [h for h in snap.health if h.kind == "tuio"]
    assert h.warnings == {} and h.errors == {}
    # the counter was not reset by -1: a drag with fseq 42 is applied, a stale 39 is late
    src.feed(ob.tuio_bundle("2Dcur", ids, [(5, 0.6, 0.8, 0.0, 0.0, 0.0)], fseq=42, source="tsim@10.0.0.3"), PEER, 1.1)
    src.feed(ob.tuio_bundle("2Dcur", ids, [(5, 0.1, 0.1, 0.0, 0.0, 0.0)], fseq=39, source="tsim@10.0.0.3"), PEER, 1.2)
    snap = src.poll(1.2)
    np.testing.assert_allclose(_pos(snap)[5], Calibration().to_arena(np.array([[0.6, 0.8]]))[0], atol=1e-6)
    (h,) = [h for h in snap.health if h.kind == "tuio"]
    assert h.warnings == {"late": 1}


def test_tuiopad_blob_sharing_a_cursor_session_id_is_not_a_second_finger():
    src = InputSource()
    cur = ob.tuio_messages("2Dcur", [3], [(3, 0.5, 0.5, 0.0, 0.0, 0.0)], fseq=9, source="TuioPad@10.0.0.4")
    blb = ob.tuio_messages("2Dblb", [3, 4], [(3, 0.5, 0.5, 0.0, 0.02, 0.02, 0.0004, 0.0, 0.0, 0.0, 0.0, 0.0),
                                              (4, 0.2, 0.2, 0.0, 0.05, 0.05, 0.0025, 0.0, 0.0, 0.0, 0.0, 0.0)],
                           fseq=9, source="TuioPad@10.0.0.4")
    src.feed(ob.bundle(*cur), PEER, 0.0)
    src.feed(ob.bundle(*blb), PEER, 0.0)
    snap = src.poll(0.0)
    by_id = {c.id: c for c in snap.contacts}
    assert sorted(by_id) == [3, 4]
    assert by_id[3].kind == "cursor" and by_id[4].kind == "blob"
    area_m2 = 0.0004 * 3.2 * 2.0
    assert by_id[3].size == pytest.approx(2 * np.sqrt(area_m2 / np.pi), rel=1e-5)
    np.testing.assert_allclose(by_id[3].position, [0.0, 0.0], atol=1e-9)
    assert _events(snap) == [("down", 3), ("down", 4)]


def test_python_tuio_single_bundle_for_all_profiles_with_one_fseq():
    """python-tuio's server: one bundle with every profile's ALIVE and SETs and a
    single `fseq -1` on 2Dcur only — 2Dobj and 2Dblb commit at the datagram end."""
    msgs = (ob.tuio_messages("2Dcur", [1], [(1, 0.1, 0.2, 0.0, 0.0, 0.0)])
            + ob.tuio_messages("2Dobj", [2], [(2, 9, 0.3, 0.4, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)])
            + ob.tuio_messages("2Dblb", [3], [(3, 0.5, 0.6, 0.0, 0.1, 0.1, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0)])
            + [ob.message("/tuio/2Dcur", "si", "fseq", -1)])
    src = InputSource()
    src.feed(ob.bundle(*msgs), PEER, 0.0)
    snap = src.poll(0.0)
    assert {(c.id, c.kind) for c in snap.contacts} == {(1, "cursor"), (2, "object"), (3, "blob")}
    src.feed(ob.bundle(*(ob.tuio_messages("2Dcur", [1]) + ob.tuio_messages("2Dobj", [])
                         + ob.tuio_messages("2Dblb", [3]) + [ob.message("/tuio/2Dcur", "si", "fseq", -1)])), PEER, 0.1)
    snap = src.poll(0.1)
    assert {c.id for c in snap.contacts} == {1, 3}
    assert _events(snap) == [("up", 2)]


def test_ccv_style_2dcur_with_width_and_height_gives_a_size():
    src = InputSource()
    src.feed(ob.bundle(ob.message("/tuio/2Dcur", "siffffff" + "f", "set", 1, 0.5, 0.5, 0.0, 0.0, 0.0, 0.1, 0.1),
                       ob.message("/tuio/2Dcur", "si", "alive", 1), ob.message("/tuio/2Dcur", "si", "fseq", 1)), PEER, 0.0)
    (c,) = src.poll(0.0).contacts
    assert c.size == pytest.approx(2 * np.sqrt(0.01 * 6.4 / np.pi), rel=1e-5)


def test_per_source_calibration_by_glob():
    cfg = ListenerConfig(source_calibrations=(("*TuioPad@*", Calibration(flip_x=True)),))
    src = InputSource(cfg)
    src.feed(ob.tuio_bundle("2Dcur", [1], ob.cursor_sets([(1, 0.0, 0.0)]), fseq=1, source="TuioPad@1.2.3.4"), PEER, 0.0)
    src.feed(ob.tuio_bundle("2Dcur", [1], ob.cursor_sets([(1, 0.0, 0.0)]), fseq=1, source="tsim@1.2.3.4"), PEER, 0.0)
    pos = {c.source.rsplit("/", 1)[1]: tuple(np.round(c.position, 6)) for c in src.poll(0.0).contacts}
    assert pos == {"TuioPad@1.2.3.4": (1.6, 1.0), "tsim@1.2.3.4": (-1.6, 1.0)}
