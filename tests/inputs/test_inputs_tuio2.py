"""TUIO 2.0: /tuio2/frm … ptr/tok/bnd … /tuio2/alv (notes/tuio.md §2)."""
from __future__ import annotations

import time

import numpy as np
import pytest

from swarmdeck.inputs import Calibration, InputSource
from swarmdeck.inputs import oscbuild as ob

PEER = ("10.0.0.7", 3333)
CAL = Calibration()
SRC = "REAC:0@0x80000001"


def ptr(sid, x, y, press=1.0, radius=0.0, vel=None):
    args = [sid, 0x00020005, 1, x, y, 0.0, 0.0, radius, press]
    tags = "iii" + "f" * 6
    if vel is not None:
        args += [vel[0], vel[1], 0.0, 0.0, 0.0]
        tags += "fffff"
    return ("ptr", tags, args)


def tok(sid, cls, x, y):
    return ("tok", "iii" + "fff", [sid, 0, cls, x, y, 0.5])


def bnd(sid, x, y, area):
    return ("bnd", "i" + "f" * 6, [sid, x, y, 0.0, 0.1, 0.1, area])


def frame(fid, comps, alive, t=None, source=SRC):
    return ob.tuio2_frame(fid, source, comps, alive, time=t)


def arena(u, v):
    return CAL.to_arena(np.array([[u, v]]))[0]


def test_pointer_token_and_bounds_become_contacts():
    src = InputSource()
    src.feed(frame(1, [ptr(1, 0.5, 0.5, vel=(0.5, 0.0)), tok(2, 17, 0.25, 0.25), bnd(3, 0.75, 0.75, 0.01)], [1, 2, 3]), PEER, 0.0)
    snap = src.poll(0.0)
    by = {c.id: c for c in snap.contacts}
    assert {i: (c.kind, c.class_id) for i, c in by.items()} == {1: ("pointer", 1), 2: ("token", 17), 3: ("bounds", None)}
    assert by[1].source == "udp://10.0.0.7/tuio2/REAC:0@0x80000001"
    np.testing.assert_allclose(by[1].velocity, [1.6, 0.0], atol=1e-6)
    np.testing.assert_allclose(by[2].velocity, [0.0, 0.0])  # no velocity tail and no motion yet
    np.testing.assert_allclose(by[3].position, arena(0.75, 0.75), atol=1e-6)
    assert by[1].pressure == pytest.approx(1.0)


def test_bounds_sharing_a_pointer_id_gives_it_a_size():
    src = InputSource()
    src.feed(frame(1, [ptr(1, 0.5, 0.5), bnd(1, 0.5, 0.5, 0.02)], [1]), PEER, 0.0)
    (c,) = src.poll(0.0).contacts
    assert c.kind == "pointer"
    assert c.size == pytest.approx(2 * np.sqrt(0.02 * 6.4 / np.pi), rel=1e-5)


def test_hovering_pointer_is_not_a_contact():
    src = InputSource()
    src.feed(frame(1, [ptr(1, 0.5, 0.5, press=-0.3), bnd(1, 0.5, 0.5, 0.02)], [1]), PEER, 0.0)
    assert src.poll(0.0).contacts == ()
    src.feed(frame(2, [ptr(1, 0.5, 0.5, press=0.4)], [1]), PEER, 0.1)
    snap = src.poll(0.1)
    assert [(e.kind, e.id) for e in snap.events] == [("down", 1)]


def test_alv_removes_and_late_frames_within_one_second_are_dropped():
    src = InputSource()
    t0 = time.time()
    src.feed(frame(10, [ptr(1, 0.5, 0.5), ptr(2, 0.2, 0.2)], [1, 2], t=t0), PEER, 0.0)
    src.feed(frame(11, [], [2], t=t0 + 0.02), PEER, 0.02)
    snap = src.poll(0.02)
    assert [c.id for c in snap.contacts] == [2]
    src.feed(frame(9, [ptr(1, 0.1, 0.1), ptr(2, 0.9, 0.9)], [1, 2], t=t0 + 0.01), PEER, 0.03)
    snap = src.poll(0.03)
    assert [c.id for c in snap.contacts] == [2] and snap.events == ()
    assert {k: v for h in snap.health for k, v in h.warnings.items()} == {"late": 1}


def test_lower_frame_id_a_second_later_is_a_restart_and_zero_is_never_late():
    src = InputSource()
    t0 = time.time()
    src.feed(frame(500, [ptr(1, 0.5, 0.5)], [1], t=t0), PEER, 0.0)
    src.feed(frame(0, [ptr(1, 0.6, 0.5)], [1], t=t0 + 0.1), PEER, 0.1)
    assert np.allclose(src.poll(0.1).contacts[0].position, arena(0.6, 0.5), atol=1e-6)
    src.feed(frame(2, [ptr(1, 0.7, 0.5)], [1], t=t0 + 1.5), PEER, 1.5)
    snap = src.poll(1.5)
    assert [(e.kind, e.id) for e in snap.events] == [("up", 1), ("down", 1)]
    assert {k: v for h in snap.health for k, v in h.warnings.items()} == {"restart": 1}


def test_unknown_and_ignored_tuio2_messages_are_counted():
    src = InputSource()
    src.feed(ob.bundle(ob.message("/tuio2/frm", "itis", 1, None, 0, SRC),
                       ob.message("/tuio2/sym", "iiiss", 1, 0, 0, "fidtrk/18", "0122212221221221"),
                       ob.message("/tuio2/zzz", "i", 1),
                       ob.message("/tuio2/ptr", "iiif", 1, 0, 0, 0.5),
                       ob.message("/tuio2/alv", "")), PEER, 0.0)
    snap = src.poll(0.0)
    (h,) = [h for h in snap.health if h.kind == "tuio2"]
    assert h.warnings == {"ignored_sym": 1}
    assert h.errors == {"unknown_profile": 1, "bad_args": 1}
    assert "ptr" in h.last_error
