"""Silent sources are lost after the timeout (virtual clock); their bumps fade out."""
from __future__ import annotations

import numpy as np

from swarmdeck.inputs import ContactDensity, DensityConfig, InputSource, ListenerConfig, PointStreamConfig
from swarmdeck.inputs import oscbuild as ob

PEER = ("10.0.0.2", 50000)


def frame(fseq, ids=(1,), x=0.5):
    return ob.tuio_bundle("2Dcur", list(ids), [(s, x, 0.5, 0.0, 0.0, 0.0) for s in ids], fseq=fseq, source="pad@h")


def kinds(snap):
    return [(e.kind, e.id) for e in snap.events]


def test_silent_source_is_lost_after_the_default_one_second():
    src = InputSource()
    src.feed(frame(1, ids=(1, 2)), PEER, 10.0)
    src.poll(10.0)
    assert len(src.poll(11.0).contacts) == 2  # exactly 1 s: not yet
    snap = src.poll(11.001)
    assert snap.contacts == ()
    assert kinds(snap) == [("lost", 1), ("lost", 2), ("source_lost", None)]
    (h,) = [h for h in snap.health if h.kind == "tuio"]
    assert h.lost and h.contacts == 0
    assert src.poll(20.0).events == ()  # reported once


def test_timeout_is_configurable():
    src = InputSource(ListenerConfig(timeout=0.25))
    src.feed(frame(1), PEER, 0.0)
    assert len(src.poll(0.25).contacts) == 1
    assert src.poll(0.26).contacts == ()


def test_refresh_bundles_keep_a_source_alive_but_late_frames_do_not():
    src = InputSource()
    src.feed(frame(50), PEER, 0.0)
    for k in range(1, 6):
        src.feed(frame(-1), PEER, 0.8 * k)  # TUIO Simulator style refresh
        assert len(src.poll(0.8 * k + 0.5).contacts) == 1
    src.feed(frame(51), PEER, 4.5)
    for k in range(1, 4):
        src.feed(frame(10), PEER, 4.5 + 0.4 * k)  # late: not a sign of life
    assert src.poll(5.6).contacts == ()


def test_sender_restarting_with_low_frame_numbers_is_accepted_after_loss():
    src = InputSource()
    src.feed(frame(90), PEER, 0.0)
    src.poll(2.0)  # lost
    src.feed(frame(1, x=0.2), PEER, 2.1)  # 90 - 1 < 100 would be "late" without the reset
    snap = src.poll(2.1)
    assert kinds(snap) == [("down", 1)]


def test_source_coming_back_gets_new_down_events_and_health_recovers():
    src = InputSource()
    src.feed(frame(1), PEER, 0.0)
    src.poll(5.0)
    src.feed(frame(2), PEER, 5.5)
    snap = src.poll(5.5)
    assert kinds(snap) == [("down", 1)]
    assert not [h for h in snap.health if h.lost]


def test_point_stream_points_expire_after_their_presence_timeout():
    cfg = ListenerConfig(tuio=False, streams=(PointStreamConfig("pad", "/pt/{id}", id_fields=("id",), presence_timeout=0.2),))
    src = InputSource(cfg)
    src.feed(ob.message("/pt/a", "ff", 0.5, 0.5), PEER, 0.0)
    src.feed(ob.message("/pt/b", "ff", 0.2, 0.2), PEER, 0.0)
    src.feed(ob.message("/pt/b", "ff", 0.3, 0.2), PEER, 0.15)
    snap = src.poll(0.3)
    assert [c.id for c in snap.contacts] == [1]
    assert kinds(snap)[-1] == ("up", 0)
    snap = src.poll(1.2)  # whole stream silent for > 1 s
    assert kinds(snap) == [("lost", 1), ("source_lost", None)]


def test_lost_contact_bump_fades_out_instead_of_vanishing():
    cfg = DensityConfig(fade=0.4)
    dens = ContactDensity(cfg)
    src = InputSource()
    src.feed(frame(1), PEER, 0.0)
    t = 0.0
    weights = []
    while t < 2.0:
        snap = src.poll(t)
        dens.update(snap.contacts, t)
        g = dens.at(t)
        weights.append((t, float(g.weight.sum()), g.n_bumps))
        t = round(t + 0.05, 10)
    w = dict((round(a, 2), b) for a, b, _ in weights)
    assert w[0.0] == 0.0 and w[0.4] == 1.0            # faded in over 0.4 s
    assert w[1.0] == 1.0                              # still there at the timeout
    assert 0.0 < w[1.2] < 1.0                         # fading after the loss at t = 1.05
    assert w[1.5] == 0.0
    steps = np.diff([b for _, b, _ in weights])
    assert np.max(np.abs(steps)) < 0.3                # no jump to zero
    assert weights[-1][2] == 0                        # faded bumps are dropped
