"""Bounded state under many ephemeral peers, and bad arguments to feed()."""
from __future__ import annotations

import math

from swarmdeck.inputs import InputSource
from swarmdeck.inputs import oscbuild as ob
from swarmdeck.inputs.contacts import MAX_SOURCES


def test_thousands_of_one_shot_peers_do_not_grow_state_without_bound():
    src = InputSource()
    data = ob.tuio_bundle("2Dcur", [], [], fseq=1)
    n = MAX_SOURCES + 300
    for k in range(n):  # e.g. one-shot senders on many hosts
        src.feed(data, (f"10.1.{k // 250}.{k % 250}", 10000 + k), 0.001 * k)
    src.feed(ob.tuio_bundle("2Dcur", [1], ob.cursor_sets([(1, 0.5, 0.5)]), fseq=1), ("10.0.0.2", 1), n * 0.001)
    snap = src.poll(n * 0.001)
    assert len(src.health(n * 0.001)) <= MAX_SOURCES + 1  # + the listener's totals
    assert [c.source for c in snap.contacts] == ["udp://10.0.0.2/tuio"]
    assert len(src._tuio._groups) <= 1024 and len(src._table._sources) <= MAX_SOURCES


def test_bad_feed_arguments_are_counted_not_raised():
    src = InputSource()
    src.feed(b"/a\x00\x00", ("h", 1), math.nan)
    src.feed(object(), ("h", 1), 0.0)  # type: ignore[arg-type]
    src.feed(b"/a\x00\x00", ("h", 1), "soon")  # type: ignore[arg-type]
    (h,) = [h for h in src.health(0.0) if h.kind == "peer"]
    assert h.errors == {"bad_feed": 3}
    assert "finite" in h.last_error or "bytes" in h.last_error
