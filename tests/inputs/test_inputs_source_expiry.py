"""Idle sources are forgotten (their counters live on in the listener's lifetime totals),
and what a poll hands to the console — hence what every Frame carries — stays small
after thousands of one-shot senders."""
from __future__ import annotations

import json

from swarmdeck.console.runtime.loop import ControlLoop, DensityParams, LoopConfig
from swarmdeck.inputs import InputHub, InputSource, ListenerConfig
from swarmdeck.inputs import oscbuild as ob

SENDERS = 1200  # the report had 3000; more than MAX_SOURCES (1024) entries is what matters
GOOD = ob.tuio_bundle("2Dcur", [1], ob.cursor_sets([(1, 0.5, 0.5)]), fseq=1)


def one_shot_senders(src: InputSource, n: int = SENDERS, t0: float = 0.0) -> float:
    """``n`` senders from distinct hosts, each: one garbage datagram, one bad SET, one frame."""
    t = t0
    bad_set = ob.bundle(ob.message("/tuio/2Dcur", "sisf", "set", 1, "x", 0.5))
    for k in range(n):
        t += 0.002
        peer = (f"10.{k // 250}.{k % 250}.9", 40000 + k)
        src.feed(b"garbage!", peer, t)
        src.feed(bad_set, peer, t)
        src.feed(GOOD, peer, t)
    return t


def test_idle_sources_are_forgotten_but_the_totals_are_kept():
    src = InputSource(ListenerConfig(forget_after=5.0))
    t = one_shot_senders(src)
    src.poll(t)
    later = t + 5.5
    snap = src.poll(later)
    assert src.work().sources_tracked == 0  # every entry expired ...
    assert src.work().sources_forgotten >= 2 * SENDERS
    (total,) = [h for h in snap.health if h.kind == "listener"]
    assert len(snap.health) == 1
    assert total.errors["not_osc"] == SENDERS and total.errors["bad_args"] == SENDERS  # ... the counts did not
    assert total.datagrams == 3 * SENDERS
    assert total.warnings["sources_forgotten"] == src.work().sources_forgotten
    # a source heard again starts afresh; the totals go on
    src.feed(b"garbage!", ("10.0.0.9", 1), later + 1)
    snap = src.poll(later + 1)
    (peer,) = [h for h in snap.health if h.name == "udp://10.0.0.9"]
    assert peer.errors == {"not_osc": 1}
    assert [h for h in snap.health if h.kind == "listener"][0].errors["not_osc"] == SENDERS + 1


def test_a_source_with_contacts_is_never_forgotten_while_it_has_them():
    src = InputSource(ListenerConfig(timeout=60.0, forget_after=5.0))
    src.feed(GOOD, ("10.0.0.1", 1), 0.0)
    snap = src.poll(30.0)  # silent for 30 s, but its finger lasts 60 s
    assert [c.id for c in snap.contacts] == [1]
    assert any(h.name == "udp://10.0.0.1/tuio" and h.contacts == 1 for h in snap.health)


def test_a_poll_reports_a_bounded_number_of_sources_with_the_active_ones_first():
    cfg = ListenerConfig(max_reported_sources=16)
    src = InputSource(cfg)
    t = one_shot_senders(src)
    src.feed(ob.tuio_bundle("2Dcur", [7], ob.cursor_sets([(7, 0.2, 0.2)]), fseq=1, source="TuioPad@10.99.0.1"),
             ("10.99.0.1", 5), t)
    snap = src.poll(t)
    assert len(snap.health) == 16 + 2
    names = [h.name for h in snap.health]
    assert "udp://10.99.0.1/TuioPad@10.99.0.1" in names
    (more,) = [h for h in snap.health if h.kind == "more"]
    tracked = src.work().sources_tracked
    assert more.name.endswith(f"{tracked - 16} more sources")


def test_frames_stay_small_after_thousands_of_one_shot_senders():
    clock = [0.0]
    src = InputSource()
    loop = ControlLoop(LoopConfig(seed=3, n_robots=4, density=DensityParams(moving=False)),
                       inputs=InputHub([src], clock=lambda: clock[0]), clock=lambda: clock[0])
    try:
        clock[0] = one_shot_senders(src)
        frame = loop.tick()
        inputs_health = {k: v for k, v in frame.health.items() if k not in ("robots", "commands")}
        assert len(inputs_health) <= ListenerConfig().max_reported_sources + 2
        assert len(json.dumps(dict(frame.health))) < 4000
        assert len(frame.contacts) <= ListenerConfig().max_contacts
    finally:
        loop.close()
