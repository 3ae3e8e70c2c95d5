"""Valid but heavy TUIO cannot stall the console: the work per datagram and per poll is
bounded whatever arrives. Deterministic work counts (OSC arguments decoded, contacts
kept and dropped, events and health entries handed to the tick), no timings — those are
in bench/bench_inputs.py."""
from __future__ import annotations

import pytest

from swarmdeck.inputs import ConfigError, InputConfig, InputSource, ListenerConfig
from swarmdeck.inputs import oscbuild as ob

TABLET = ("10.0.0.2", 50000)


def heavy(first_id: int, alive: int = 10_000, sets: int = 200, fseq: int = 1) -> bytes:
    """The report's datagram: an ALIVE of ``alive`` ids and ``sets`` SETs (≈ 61 kB)."""
    ids = list(range(first_id, first_id + alive))
    return ob.tuio_bundle("2Dcur", ids, ob.cursor_sets([(i, 0.5, 0.5) for i in ids[:sets]]), fseq=fseq)


def flood(first_id: int, n: int, fseq: int) -> bytes:
    """Valid and under the argument budget: ``n`` new fingers at once."""
    ids = list(range(first_id, first_id + n))
    return ob.tuio_bundle("2Dcur", ids, ob.cursor_sets([(i, 0.2, 0.2) for i in ids]), fseq=fseq)


def tablet(fseq: int) -> bytes:
    return ob.tuio_bundle("2Dcur", [1, 2], ob.cursor_sets([(1, 0.4, 0.5), (2, 0.6, 0.5)]), fseq=fseq,
                          source="TuioPad@10.0.0.2")


def totals(src: InputSource, now: float):
    (h,) = [h for h in src.health(now) if h.kind == "listener"]
    return h


def test_defaults_are_far_above_what_a_tablet_sends():
    c = ListenerConfig()
    assert (c.max_contacts_per_source, c.max_contacts, c.max_osc_arguments) == (64, 256, 2048)
    # a 64-finger 2Dblb frame (the largest SET) fits in one datagram's budget
    ids = list(range(64))
    blobs = [(i, 0.5, 0.5, 0.0, 0.1, 0.1, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0) for i in ids]
    src = InputSource()
    src.feed(ob.tuio_bundle("2Dblb", ids, blobs, fseq=1, source="table"), TABLET, 0.0)
    assert len(src.poll(0.0).contacts) == 64 and not totals(src, 0.0).errors


def test_the_reported_datagram_is_rejected_before_it_is_decoded():
    src = InputSource()
    src.feed(tablet(1), TABLET, 0.0)
    decoded = src.work().arguments_decoded
    big = heavy(5000)
    for k in range(20):
        src.feed(heavy(1000 + 200 * (k % 2), fseq=k + 1) if k < 2 else big, ("10.6.6.6", 4000 + k), 0.01 * k)
    work = src.work()
    assert work.arguments_decoded == decoded  # python-osc never saw them
    assert work.datagrams == 21
    h = totals(src, 0.2)
    assert h.errors == {"too_many_arguments": 20}
    (peer,) = [x for x in src.health(0.2) if x.name == "udp://10.6.6.6"]
    assert peer.errors == {"too_many_arguments": 20} and "more than the limit of 2048" in peer.last_error
    assert sorted(c.id for c in src.poll(0.2).contacts) == [1, 2]  # the tablet's fingers are untouched


def test_contacts_are_capped_per_source_and_in_total_and_the_excess_is_counted():
    src = InputSource(ListenerConfig(max_contacts_per_source=64, max_contacts=256))
    src.feed(tablet(1), TABLET, 0.0)
    t = 0.0
    for host in range(6):  # six flooding hosts, 200 new fingers per datagram, 5 datagrams each
        for k in range(5):
            t += 0.001
            src.feed(flood(10_000 * host + 200 * k, 200, k + 1), (f"10.7.7.{host}", 9), t)
    snap = src.poll(t)
    per = {}
    for c in snap.contacts:
        per[c.source] = per.get(c.source, 0) + 1
    assert per["udp://10.0.0.2/TuioPad@10.0.0.2"] == 2  # the good fingers stay
    assert max(per.values()) == 64 and len(snap.contacts) == 256
    # floods: 6 hosts; each datagram replaces the host's fingers (a new ALIVE); the first
    # three keep 64 each (192 + the tablet's 2 = 194 contacts), the fourth the remaining 62,
    # the last two none; every other finger offered was dropped and counted
    offered = 6 * 5 * 200
    kept_per_host = [64, 64, 64, 62, 0, 0]
    h = totals(src, t)
    assert h.contacts == 256
    assert h.errors["too_many_contacts"] == offered - 5 * sum(kept_per_host)
    flood_health = {x.name: x for x in src.health(t) if x.name.startswith("udp://10.7.7.")}
    assert flood_health["udp://10.7.7.4/tuio"].errors["too_many_contacts"] == 1000
    assert "limit of 64 contacts per source" in flood_health["udp://10.7.7.0/tuio"].last_error


def test_the_work_handed_to_the_tick_is_bounded_whatever_arrives():
    cfg = ListenerConfig()
    src = InputSource(cfg)
    t = 0.0
    floods = [flood(1000 * k, 200, k + 1) for k in range(3)]
    big = heavy(0)
    pads = [tablet(k + 1) for k in range(80)]
    for k in range(80):  # one-shot senders, changing floods, heavy and garbage datagrams
        t += 0.001
        host = f"10.{k % 7}.{k // 7 % 250}.1"
        src.feed(floods[k % 3], (host, k), t)
        src.feed(big, (host, k), t)
        src.feed(b"\x00" * 64, (host, k), t)
        src.feed(pads[k], TABLET, t)
    work = src.work()
    assert work.arguments_decoded <= work.datagrams * cfg.max_osc_arguments
    snap = src.poll(t)
    assert len(snap.contacts) <= cfg.max_contacts
    assert len(snap.events) <= cfg.max_events
    assert len(snap.health) <= cfg.max_reported_sources + 2  # + the listener's totals + "more sources"
    assert {c.id for c in snap.contacts if c.source.endswith("TuioPad@10.0.0.2")} == {1, 2}
    h = totals(src, t)
    assert h.warnings.get("events_dropped", 0) + len(snap.events) == work.events
    assert work.sources_tracked <= 1024


@pytest.mark.parametrize("key, bad", [("max_contacts_per_source", 0), ("max_contacts", "many"),
                                      ("max_osc_arguments", 4), ("max_events", -1),
                                      ("max_reported_sources", 0), ("forget_after", float("nan"))])
def test_limits_are_configurable_and_checked(key, bad):
    cfg = InputConfig.from_dict({"listeners": [{"max_contacts_per_source": 8, "max_contacts": 16}]})
    assert cfg.listeners[0].max_contacts_per_source == 8 and cfg.listeners[0].max_contacts == 16
    with pytest.raises(ConfigError, match=key):
        InputConfig.from_dict({"listeners": [{key: bad}]})
