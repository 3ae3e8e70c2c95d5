"""TUIO state is keyed by the sending host and the TUIO source string, not by the UDP
port: each `oscsend` run (and each TCP reconnect) comes from a new port but moves the
same finger, and an empty ALIVE from yet another port lifts it."""
from __future__ import annotations

import numpy as np

from swarmdeck.inputs import Calibration, InputSource
from swarmdeck.inputs import oscbuild as ob

CAL = Calibration()


def one_message_each(src: InputSource, host: str, port0: int, t: float, *messages: bytes) -> int:
    for k, m in enumerate(messages):
        src.feed(m, (host, port0 + k), t)
    return port0 + len(messages)


def test_single_messages_from_new_ports_move_and_lift_one_finger():
    src = InputSource()
    cur = "/tuio/2Dcur"
    port = one_message_each(src, "127.0.0.1", 40000, 0.0, ob.message(cur, "si", "alive", 1),
                            ob.message(cur, "sifffff", "set", 1, 0.5, 0.5, 0.0, 0.0, 0.0),
                            ob.message(cur, "si", "fseq", 1))
    snap = src.poll(0.0)
    assert [(e.kind, e.id) for e in snap.events] == [("down", 1)]
    port = one_message_each(src, "127.0.0.1", port, 0.1, ob.message(cur, "sifffff", "set", 1, 0.6, 0.5, 0, 0, 0),
                            ob.message(cur, "si", "fseq", 2))
    snap = src.poll(0.1)
    (c,) = snap.contacts  # the same finger, moved: not a second one
    assert c.id == 1 and [(e.kind, e.id) for e in snap.events] == [("move", 1)]
    np.testing.assert_allclose(c.position, CAL.to_arena(np.array([[0.6, 0.5]]))[0], atol=1e-6)
    one_message_each(src, "127.0.0.1", port, 0.2, ob.message(cur, "s", "alive"))
    snap = src.poll(0.2)
    assert snap.contacts == () and [(e.kind, e.id) for e in snap.events] == [("up", 1)]
    assert not any(h.errors or h.warnings for h in snap.health)


def test_a_source_string_follows_the_sender_across_ports_and_hosts_stay_apart():
    src = InputSource()
    for k in range(3):  # a TCP tablet reconnecting: a new port each time, the same source
        data = ob.tuio_bundle("2Dcur", [3], ob.cursor_sets([(3, 0.1 * (k + 1), 0.5)]), fseq=k + 1,
                              source="TuioPad@10.0.0.2")
        src.feed(data, ("10.0.0.2", 50000 + k), 0.1 * k)
    src.feed(ob.tuio_bundle("2Dcur", [3], ob.cursor_sets([(3, 0.9, 0.9)]), fseq=1, source="TuioPad@10.0.0.2"),
             ("10.0.0.3", 50000), 0.2)  # another host with the same string: its own finger
    snap = src.poll(0.2)
    kinds = [(e.kind, e.source) for e in snap.events]
    assert kinds == [("down", "udp://10.0.0.2/TuioPad@10.0.0.2"), ("move", "udp://10.0.0.2/TuioPad@10.0.0.2"),
                     ("move", "udp://10.0.0.2/TuioPad@10.0.0.2"), ("down", "udp://10.0.0.3/TuioPad@10.0.0.2")]
    assert not any(h.warnings for h in snap.health)  # no "late" frames: one frame counter per source
