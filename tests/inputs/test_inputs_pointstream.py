"""Generic OSC point streams and the gesture-bridge presets."""
from __future__ import annotations

import time

import numpy as np
import pytest
from pythonosc.udp_client import SimpleUDPClient

from swarmdeck.inputs import PRESETS, Calibration, InputSource, ListenerConfig, PointStreamConfig, UdpListener
from swarmdeck.inputs import oscbuild as ob

PEER = ("127.0.0.1", 7000)
CAL = Calibration()


def src_for(preset: str) -> InputSource:
    return InputSource(ListenerConfig.from_preset(preset))


def test_manososc_fingers_are_points_keyed_by_hand_and_finger():
    src = src_for("manososc")
    assert ListenerConfig.from_preset("manososc").port == 7110
    # /finger<h>-<f>  s name, i hand, i finger, f x, f y, f z (Leap mm; x right, z towards the user)
    src.feed(ob.bundle(ob.message("/finger0-1", "siifff", "index", 0, 1, 0.0, 180.0, 0.0),
                       ob.message("/finger0-2", "siifff", "middle", 0, 2, 100.0, 180.0, -75.0)), PEER, 0.0)
    snap = src.poll(0.0)
    pos = {c.id: c.position for c in snap.contacts}
    np.testing.assert_allclose(pos[0], CAL.to_arena(np.array([[0.5, 0.5]]))[0], atol=1e-9)
    np.testing.assert_allclose(pos[1], CAL.to_arena(np.array([[0.75, 0.25]]))[0], atol=1e-6)
    assert {c.kind for c in snap.contacts} == {"point"}
    src.feed(ob.message("/finger0-2", "siifff", "middle", 0, 2, 100.0, 180.0, 0.0), PEER, 0.1)
    snap = src.poll(0.1)
    assert [(e.kind, e.id) for e in snap.events] == [("move", 1)]
    c1 = [c for c in snap.contacts if c.id == 1][0]
    assert c1.velocity[1] < 0  # moved towards the user = down the arena


def test_leap_osc_finger_positions():
    src = src_for("leap-osc")
    src.feed(ob.message("/leap/0/3/pos", "fff", -200.0, 150.0, 150.0), PEER, 0.0)
    src.feed(ob.message("/leap/0/palm_pos", "fff", 0.0, 150.0, 0.0), PEER, 0.0)  # not a finger
    snap = src.poll(0.0)
    (c,) = snap.contacts
    np.testing.assert_allclose(c.position, [-1.6, -1.0], atol=1e-9)
    assert c.source == "udp://127.0.0.1/leap-osc"
    (peer,) = [h for h in snap.health if h.kind == "peer"]
    assert peer.warnings == {"unmatched_address": 1}


def test_ultraleap_palms_over_a_real_socket_from_python_osc():
    cfg = ListenerConfig.from_preset("ultraleap-osc-sender", port=0)
    assert ListenerConfig.from_preset("ultraleap-osc-sender").port == 5000
    with UdpListener(cfg, clock=lambda: 3.0) as lst:
        client = SimpleUDPClient("127.0.0.1", lst.address[1])
        client.send_message("/leap/left", [-100.0, 200.0, 0.0])   # python-osc infers f for floats
        client.send_message("/leap/right", [100.0, 200.0, 0.0])
        end = time.monotonic() + 5
        while len(lst.contacts()) < 2 and time.monotonic() < end:
            time.sleep(0.002)
        snap = lst.poll(3.0)
    xs = sorted(round(float(c.position[0]), 6) for c in snap.contacts)
    assert xs == [-0.8, 0.8]


def test_bad_point_messages_are_counted_with_reasons():
    src = src_for("ultraleap-osc-sender")
    src.feed(ob.message("/leap/left", "ff", 1.0, 2.0), PEER, 0.0)
    src.feed(ob.message("/leap/left", "fsf", 1.0, "x", 2.0), PEER, 0.0)  # y is argument 2: fine
    src.feed(ob.message("/leap/left", "sff", "x", 1.0, 2.0), PEER, 0.0)
    src.feed(ob.message("/leap/left", "fff", float("nan"), 1.0, 2.0), PEER, 0.0)
    src.feed(ob.message("/leap/left", "fff", 5000.0, 1.0, 0.0), PEER, 0.0)  # way outside: clamped
    snap = src.poll(0.0)
    (h,) = [h for h in snap.health if h.kind == "points"]
    assert h.errors == {"bad_args": 2, "non_finite": 1}
    assert h.warnings == {"out_of_range": 1}
    assert h.last_error == "/leap/left has NaN or inf coordinates"
    (c,) = snap.contacts
    assert c.position[0] == pytest.approx(1.6)


def test_custom_stream_with_flips_units_and_an_argument_id():
    s = PointStreamConfig("xy", "/touch", x_arg=1, y_arg=2, id_fields=(0,), scale=0.01,
                          x_range=(0.0, 1.0), y_range=(0.0, 1.0), flip_y=True)
    src = InputSource(ListenerConfig(tuio=False, streams=(s,)))
    src.feed(ob.message("/touch", "iii", 42, 25, 0), PEER, 0.0)  # ints accepted as numbers
    (c,) = src.poll(0.0).contacts
    np.testing.assert_allclose(c.position, CAL.to_arena(np.array([[0.25, 1.0]]))[0])
    with pytest.raises(ValueError, match="id field 'hand'"):
        PointStreamConfig("bad", "/x", id_fields=("hand",))
    with pytest.raises(ValueError, match="start with '/'"):
        PointStreamConfig("bad", "x")


def test_presets_are_documented_names():
    assert set(PRESETS) == {"manososc", "leap-osc", "ultraleap-osc-sender"}
