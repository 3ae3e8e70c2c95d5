"""Frame ordering of TUIO 1.1: late, equal, restart, −1/0, missing FSEQ,
unbundled messages, SETs outside ALIVE, two sources with overlapping session ids."""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.inputs import Calibration, InputSource
from swarmdeck.inputs import oscbuild as ob

PEER = ("10.0.0.2", 50000)
CAL = Calibration()


def frame(x: float, fseq: int | None, ids=(1,), source: str | None = "pad@10.0.0.2") -> bytes:
    return ob.tuio_bundle("2Dcur", list(ids), [(s, x, 0.5, 0.0, 0.0, 0.0) for s in ids], fseq=fseq, source=source)


def xs(snap) -> dict[int, float]:
    return {c.id: round(float(c.position[0]), 6) for c in snap.contacts}


def arena_x(u: float) -> float:
    return round(float(CAL.to_arena(np.array([[u, 0.5]]))[0, 0]), 6)


def warnings(snap) -> dict[str, int]:
    return {k: v for h in snap.health if h.kind == "tuio" for k, v in h.warnings.items()}


def test_late_frame_is_dropped():
    src = InputSource()
    src.feed(frame(0.5, 10), PEER, 0.0)
    src.feed(frame(0.2, 9), PEER, 0.01)
    snap = src.poll(0.01)
    assert xs(snap) == {1: arena_x(0.5)}
    assert warnings(snap) == {"late": 1}


def test_equal_fseq_is_applied():
    src = InputSource()
    src.feed(frame(0.5, 10), PEER, 0.0)
    src.feed(frame(0.6, 10), PEER, 0.01)
    assert xs(src.poll(0.01)) == {1: arena_x(0.6)}


def test_restart_after_a_backward_jump_over_100_ends_old_contacts():
    src = InputSource()
    src.feed(frame(0.5, 500), PEER, 0.0)
    src.poll(0.0)
    src.feed(frame(0.3, 3), PEER, 0.01)
    snap = src.poll(0.01)
    assert xs(snap) == {1: arena_x(0.3)}
    assert [(e.kind, e.id) for e in snap.events] == [("up", 1), ("down", 1)]
    assert warnings(snap) == {"restart": 1}
    src.feed(frame(0.4, 4), PEER, 0.02)  # counting goes on from the new start
    assert xs(src.poll(0.02)) == {1: arena_x(0.4)}


def test_backward_jump_of_exactly_100_is_late():
    src = InputSource()
    src.feed(frame(0.5, 200), PEER, 0.0)
    src.feed(frame(0.3, 100), PEER, 0.01)
    assert xs(src.poll(0.01)) == {1: arena_x(0.5)}


def test_minus_one_and_zero_are_never_late_and_keep_the_counter():
    src = InputSource()
    src.feed(frame(0.5, 50), PEER, 0.0)
    src.feed(frame(0.6, -1), PEER, 0.01)
    assert xs(src.poll(0.01)) == {1: arena_x(0.6)}
    src.feed(frame(0.7, 0), PEER, 0.02)
    assert xs(src.poll(0.02)) == {1: arena_x(0.7)}
    src.feed(frame(0.1, 49), PEER, 0.03)  # still late against 50
    snap = src.poll(0.03)
    assert xs(snap) == {1: arena_x(0.7)}
    assert warnings(snap) == {"late": 1}


def test_missing_fseq_commits_at_the_end_of_the_datagram():
    src = InputSource()
    src.feed(frame(0.5, None), PEER, 0.0)
    assert xs(src.poll(0.0)) == {1: arena_x(0.5)}
    src.feed(ob.tuio_bundle("2Dcur", [], [], fseq=None, source="pad@10.0.0.2"), PEER, 0.1)
    assert xs(src.poll(0.1)) == {}


def test_unbundled_messages_one_per_datagram():
    """Senders such as Max patches or `oscsend` send each message on its own."""
    src = InputSource()
    for i, m in enumerate(ob.tuio_messages("2Dcur", [4], [(4, 0.25, 0.5, 0.0, 0.0, 0.0)], fseq=1)):
        src.feed(m, PEER, 0.001 * i)
    assert xs(src.poll(0.01)) == {4: arena_x(0.25)}
    src.feed(ob.message("/tuio/2Dcur", "sifffff", "set", 4, 0.75, 0.5, 0.0, 0.0, 0.0), PEER, 0.02)
    assert xs(src.poll(0.02)) == {4: arena_x(0.75)}


def test_set_for_an_id_outside_alive_is_ignored():
    src = InputSource()
    src.feed(ob.tuio_bundle("2Dcur", [1], [(1, 0.5, 0.5, 0, 0, 0), (2, 0.1, 0.1, 0, 0, 0)], fseq=1), PEER, 0.0)
    snap = src.poll(0.0)
    assert xs(snap) == {1: arena_x(0.5)}
    assert warnings(snap) == {"set_not_alive": 1}


def test_alive_id_without_a_set_is_not_a_contact_until_its_set():
    src = InputSource()
    src.feed(ob.tuio_bundle("2Dcur", [1, 2], [(1, 0.5, 0.5, 0, 0, 0)], fseq=1), PEER, 0.0)
    assert xs(src.poll(0.0)) == {1: arena_x(0.5)}
    src.feed(ob.tuio_bundle("2Dcur", [1, 2], [(2, 0.1, 0.5, 0, 0, 0)], fseq=2), PEER, 0.1)
    assert xs(src.poll(0.1)) == {1: arena_x(0.5), 2: arena_x(0.1)}


def test_two_sources_on_one_peer_with_overlapping_session_ids():
    src = InputSource()
    src.feed(frame(0.2, 1000, source="a@1"), PEER, 0.0)
    src.feed(frame(0.8, 5, source="b@2"), PEER, 0.0)  # its own counter: not late
    snap = src.poll(0.0)
    assert sorted((c.source, c.id) for c in snap.contacts) == [
        ("udp://10.0.0.2/a@1", 1), ("udp://10.0.0.2/b@2", 1)]
    src.feed(ob.tuio_bundle("2Dcur", [], [], fseq=1001, source="a@1"), PEER, 0.1)  # a's ALIVE is empty
    snap = src.poll(0.1)
    assert [(c.source, c.id) for c in snap.contacts] == [("udp://10.0.0.2/b@2", 1)]
    assert warnings(snap) == {}


def test_two_peers_without_source_strings_are_separate():
    src = InputSource()
    src.feed(frame(0.2, 1000, source=None), ("10.0.0.5", 1), 0.0)
    src.feed(frame(0.8, 5, source=None), ("10.0.0.6", 1), 0.0)
    src.feed(ob.tuio_bundle("2Dcur", [], [], fseq=1001), ("10.0.0.5", 1), 0.1)
    snap = src.poll(0.1)
    assert [(c.source, c.id) for c in snap.contacts] == [("udp://10.0.0.6/tuio", 1)]


def test_source_string_does_not_leak_into_the_next_datagram():
    """The reference C++ client credits a bundle without SOURCE to the last source seen."""
    src = InputSource()
    src.feed(frame(0.2, 1, source="a@1"), PEER, 0.0)
    src.feed(frame(0.8, 1, source=None, ids=(9,)), PEER, 0.0)
    assert sorted((c.source, c.id) for c in src.poll(0.0).contacts) == [
        ("udp://10.0.0.2/a@1", 1), ("udp://10.0.0.2/tuio", 9)]


@settings(max_examples=60, deadline=None)
@given(first=st.integers(101, 10_000), back=st.integers(1, 100), x=st.floats(0, 1))
def test_any_frame_up_to_100_behind_the_last_is_ignored(first, back, x):
    src = InputSource()
    src.feed(frame(0.5, first), PEER, 0.0)
    before = xs(src.poll(0.0))
    src.feed(frame(x, first - back, ids=(1, 2)), PEER, 0.01)
    snap = src.poll(0.01)
    assert xs(snap) == before and snap.events == ()
