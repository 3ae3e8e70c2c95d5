"""The operator's monitor page and InputHub merging (socket-free sources)."""
from __future__ import annotations

import argparse
import io

from swarmdeck.console.cli.inputs import add_arguments, config_from_args, main
from swarmdeck.inputs import InputHub, InputSource
from swarmdeck.inputs import oscbuild as ob
from swarmdeck.inputs.monitor import render, run


def test_page_shows_sources_rates_contacts_and_errors():
    a, b = InputSource(), InputSource()
    hub = InputHub([a, b])
    for k in range(10):
        a.feed(ob.tuio_bundle("2Dcur", [3], ob.cursor_sets([(3, 0.5, 0.5)]), fseq=k + 1, source="TuioPad@10.0.0.2"),
               ("10.0.0.2", 40000), 0.1 * k)
    b.feed(b"junk", ("10.0.0.9", 1), 0.5)
    page = render(hub.poll(0.95), ("udp://127.0.0.1:3333",))
    assert "udp://10.0.0.2/TuioPad@10.0.0.2" in page
    assert "not_osc 1" in page and "last error" in page
    assert "id 3" in page and "x +0.000 y +0.000 m" in page
    assert " 10.0 " in page  # 10 frames within the last second
    page = render(hub.poll(2.5))
    assert "LOST" in page and "contacts (0)" in page


def test_same_sender_reaching_two_listeners_is_one_contact():
    a, b = InputSource(), InputSource()
    data = ob.tuio_bundle("2Dcur", [3], ob.cursor_sets([(3, 0.5, 0.5)]), fseq=1, source="reacTIVision")
    a.feed(data, ("127.0.0.1", 5), 0.0)
    b.feed(data, ("127.0.0.1", 5), 0.01)
    snap = InputHub([a, b]).poll(0.01)
    assert len(snap.contacts) == 1 and snap.contacts[0].last_seen == 0.01


def test_run_prints_pages_for_a_bounded_duration():
    p = argparse.ArgumentParser()
    add_arguments(p)
    cfg = config_from_args(p.parse_args(["monitor", "--port", "0", "--preset", "manososc"]))
    assert cfg.listeners[0].streams[0].name == "manososc" and cfg.listeners[0].port == 0
    out = io.StringIO()
    ticks = iter([0.0, 0.0, 0.1, 0.2, 0.3])
    assert run(cfg, duration=0.0, interval=0.01, out=out, clock=lambda: next(ticks)) == 0
    text = out.getvalue()
    assert text.startswith("listening on udp://127.0.0.1:") and "nothing received yet" in text


def test_send_demo_fingers_reach_a_real_listener():
    import time as _time

    import numpy as np

    from swarmdeck.inputs import ListenerConfig, UdpListener, sender

    with UdpListener(ListenerConfig(port=0), clock=lambda: 0.0) as lst:
        now = [0.0]  # virtual sender clock: advances only by the sender's sleeps

        def sleep(s):
            now[0] += s
        n = sender.run("127.0.0.1", lst.address[1], duration=0.99, rate=20.0, fingers=2,
                       clock=lambda: now[0], sleep=sleep)
        assert n == 20
        end = _time.monotonic() + 5
        events = []
        while _time.monotonic() < end and not any(e.kind == "up" for e in events):
            events += lst.poll(0.0).events
            _time.sleep(0.002)
    kinds = [(e.kind, e.id) for e in events]
    assert kinds[:2] == [("down", 1), ("down", 2)] and kinds[-2:] == [("up", 1), ("up", 2)]
    moves = [e.contact for e in events if e.kind == "move" and e.id == 1]
    assert len(moves) == 19
    # the demo circles around the arena centre: radius 0.3..1 × 0.25 of the surface
    r = [np.hypot(*(c.position / [3.2, 2.0])) for c in moves]
    assert 0.25 * 0.3 - 1e-6 <= min(r) and max(r) <= 0.25 + 1e-6


def test_cli_send_rejects_bad_values():
    p = argparse.ArgumentParser()
    add_arguments(p)
    import pytest

    from swarmdeck.console.cli import UsageError

    with pytest.raises(UsageError, match="rate > 0"):
        main(p.parse_args(["send", "--rate", "0", "--port", "9"]))
    with pytest.raises(UsageError, match="interval"):
        main(p.parse_args(["monitor", "--interval", "0"]))
