"""Raw capture → replay through the same parser on a virtual clock reproduces
contacts, events and density exactly."""
from __future__ import annotations

import numpy as np

from swarmdeck.inputs import Capture, ContactDensity, Datagram, InputSource, read_jsonl, replay, write_jsonl
from swarmdeck.inputs import oscbuild as ob


def session():
    """A live-like session: two fingers, one lifts, then the tablet dies."""
    out = []
    for k in range(20):
        ids = [1, 2] if k < 12 else [2]
        pts = [(s, 0.3 + 0.02 * k + 0.2 * (s - 1), 0.5, 0.0, 0.0, 0.0) for s in ids]
        out.append((ob.tuio_bundle("2Dcur", ids, pts, fseq=k + 1, source="pad@10.0.0.2"), 0.05 * k))
    out.append((b"garbage!", 0.97))
    return out


def run(feed_items, src, dens, until=3.0):
    log = []
    ticks = np.arange(0.0, until, 0.033)
    items = list(feed_items)
    i = 0
    for t in ticks:
        while i < len(items) and items[i][1] <= t:
            feed_one(src, items[i])
            i += 1
        snap = src.poll(t)
        dens.update(snap.contacts, t)
        g = dens.at(t)
        log.append(([(e.kind, e.id) for e in snap.events], g.mu.round(12).tolist(), g.weight.round(12).tolist()))
    return log


def feed_one(src, item):
    data, t = item[0], item[1]
    peer = item[2] if len(item) > 2 else ("10.0.0.2", 50000)
    src.feed(data, peer, t)


def test_replay_of_a_capture_reproduces_the_session(tmp_path):
    cap = Capture()
    live = InputSource(on_datagram=cap)
    live_log = run(session(), live, ContactDensity())
    caught = cap.datagrams()
    assert len(caught) == 21 and caught[0].peer == "udp://10.0.0.2:50000" and caught[-1].data == b"garbage!"
    path = tmp_path / "session.jsonl"
    write_jsonl(path, caught)
    back = list(read_jsonl(path))
    assert back == caught
    again = InputSource()
    replay_log = run([(d.data, d.t, d.peer) for d in back], again, ContactDensity())
    assert replay_log == live_log
    assert any(k == ("source_lost", None) for ev, _, _ in live_log for k in ev)
    h_live = {h.name: (h.datagrams, h.errors) for h in live.health(3.0)}
    h_again = {h.name: (h.datagrams, h.errors) for h in again.health(3.0)}
    assert h_live == h_again


def test_replay_helper_and_time_offset():
    src = InputSource()
    n = replay([Datagram(1.0, ob.tuio_bundle("2Dcur", [1], ob.cursor_sets([(1, 0.5, 0.5)]), fseq=1), "udp://h:1")],
               src, time_offset=10.0)
    assert n == 1
    (c,) = src.poll(11.0).contacts
    assert c.first_seen == 11.0 and c.source == "udp://h/tuio"


def test_bad_jsonl_line_is_named(tmp_path):
    p = tmp_path / "x.jsonl"
    p.write_text('{"t": 1, "peer": "udp://a:1", "data": "AAAA"}\n{"t": 2}\n')
    it = read_jsonl(p)
    next(it)
    try:
        next(it)
    except ValueError as exc:
        assert "x.jsonl:2" in str(exc)
    else:
        raise AssertionError("expected ValueError")
