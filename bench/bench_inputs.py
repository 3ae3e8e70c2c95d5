"""Benchmark of swarmdeck.inputs: TUIO parse/assembly throughput and latency
from datagram to updated density.

    .venv/bin/python bench/bench_inputs.py

Prints a markdown table. Ten-finger TUIO 1.1 2Dcur bundles (source, alive, 10 set,
fseq; 784 bytes) with moving fingers. Rows: python-osc ``OscBundle`` parse alone
(the baseline, same process), ``parse_datagram`` (structural checks + python-osc),
``InputSource.feed`` (parse + TUIO assembly + calibrated contacts + events), and
``feed`` + ``poll``. Latency: ``feed`` → ``poll`` → ``ContactDensity.update`` →
``.at(t)`` per datagram. Heavy traffic (issue 14 §8–9): per-datagram feed cost of the
report's heavy datagram and of a finger flood, and one poll after 1200 one-shot senders,
as ratios to feeding a ten-finger bundle. Medians over repeats of CPU time
(time.process_time: the VM is shared); one thread.
"""
from __future__ import annotations

import statistics
import sys
import time

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np
from pythonosc.osc_bundle import OscBundle

from swarmdeck.inputs import ContactDensity, InputSource, parse_datagram
from swarmdeck.inputs import oscbuild as ob

N_BUNDLES = 4000
REPEATS = 7


def make_bundles(n: int, fingers: int = 10) -> list[bytes]:
    """``n`` consecutive frames of ``fingers`` cursors moving on circles."""
    out = []
    ids = list(range(1, fingers + 1))
    for f in range(n):
        ph = 2 * np.pi * f / 120.0
        sets = [(s, 0.5 + 0.3 * np.cos(ph + s), 0.5 + 0.3 * np.sin(ph + s), 0.1, -0.1, 0.0) for s in ids]
        out.append(ob.tuio_bundle("2Dcur", ids, sets, fseq=f + 1, source="bench@127.0.0.1"))
    return out


def rate(fn, data: list[bytes]) -> float:
    """Median bundles/s of ``fn`` over ``data``."""
    return len(data) / harness.measure(lambda: fn(data), REPEATS, clock="cpu").median


def main() -> int:
    data = make_bundles(N_BUNDLES)
    peer = ("127.0.0.1", 40000)

    def python_osc(ds):
        for d in ds:
            for m in OscBundle(d):
                _ = m.params

    def ours_parse(ds):
        for d in ds:
            parse_datagram(d)

    def feed(ds):
        src = InputSource()
        t = 0.0
        for d in ds:
            t += 1 / 60
            src.feed(d, peer, t)

    def feed_poll(ds):
        src = InputSource()
        t = 0.0
        for d in ds:
            t += 1 / 60
            src.feed(d, peer, t)
            src.poll(t)

    base = rate(python_osc, data)
    rows = [("python-osc OscBundle parse + params (baseline)", base)]
    rows.append(("parse_datagram (checks + python-osc)", rate(ours_parse, data)))
    rows.append(("InputSource.feed (parse + TUIO + contacts)", rate(feed, data)))
    rows.append(("feed + poll", rate(feed_poll, data)))

    # latency: datagram -> density.at(t) reflecting it
    src = InputSource()
    dens = ContactDensity()
    lat = []
    t = 0.0
    for d in data[:2000]:
        t += 1 / 60
        t0 = time.process_time()
        src.feed(d, peer, t)
        snap = src.poll(t)
        dens.update(snap.contacts, t)
        g = dens.at(t)
        lat.append(time.process_time() - t0)
        assert g.n_bumps == 10
    lat_sorted = sorted(lat[100:])
    med = statistics.median(lat_sorted)
    p99 = lat_sorted[int(0.99 * len(lat_sorted))]

    # wall-clock latency over a real loopback socket: sendto -> listener thread ->
    # poll sees the new position -> density updated
    import socket

    from swarmdeck.inputs import ListenerConfig, UdpListener

    wall = []
    with UdpListener(ListenerConfig(port=0)) as lst:
        tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        dens2 = ContactDensity()
        for k, d in enumerate(data[:300]):
            t0 = time.perf_counter()
            tx.sendto(d, lst.address)
            while True:
                now = time.monotonic()
                snap = lst.poll(now)
                if len(snap.health) > 1 and any(h.datagrams == k + 1 for h in snap.health if h.kind == "tuio"):
                    break
            dens2.update(snap.contacts, now)
            dens2.at(now)
            wall.append(time.perf_counter() - t0)
    wall_sorted = sorted(wall[20:])
    wmed = statistics.median(wall_sorted)
    wp99 = wall_sorted[int(0.99 * len(wall_sorted))]

    heavy_rows = heavy_traffic(data[0], peer)

    print(f"inputs benchmark — {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {harness.machine()}, "
          f"{N_BUNDLES} ten-finger 2Dcur bundles of {len(data[0])} B, median of {REPEATS}")
    print()
    print("| stage | bundles/s | ratio to python-osc parse |")
    print("| --- | ---: | ---: |")
    for name, r in rows:
        print(f"| {name} | {r:,.0f} | {r / base:.2f} |")
    print()
    print("| latency, 10 fingers | median | p99 |")
    print("| --- | ---: | ---: |")
    print(f"| datagram → updated density, CPU (feed + poll + update + at) | {med * 1e6:.0f} µs | {p99 * 1e6:.0f} µs |")
    print(f"| sendto on loopback → listener thread → poll → density, wall | {wmed * 1e6:.0f} µs | {wp99 * 1e6:.0f} µs |")
    print()
    print("| heavy traffic (issue 14 §8–9) | CPU µs, median | ratio to a ten-finger feed | work |")
    print("| --- | ---: | ---: | --- |")
    for name, sec, base_s, work in heavy_rows:
        print(f"| {name} | {sec * 1e6:,.0f} | {sec / base_s:.1f} | {work} |")
    return 0


def _median_cpu(fn, repeats: int = 7) -> float:
    return harness.measure(fn, repeats, clock="cpu").median


def heavy_traffic(ten_finger: bytes, peer: tuple) -> list[tuple[str, float, float, str]]:
    """Per-datagram feed cost of the report's heavy datagram (ALIVE of 10 000 ids +
    200 SETs, rejected before decoding) and of a 200-new-finger flood (decoded, 64
    kept), and the cost of one poll — the console tick's input stage — after 1200
    one-shot senders with 256 contacts held; baseline: feeding a ten-finger bundle."""
    ids = list(range(10_000))
    heavy = ob.tuio_bundle("2Dcur", ids, ob.cursor_sets([(i, 0.5, 0.5) for i in ids[:200]]), fseq=1)
    floods = [ob.tuio_bundle("2Dcur", list(range(200 * k, 200 * k + 200)),
                             ob.cursor_sets([(i, 0.3, 0.3) for i in range(200 * k, 200 * k + 200)]), fseq=k + 1)
              for k in range(4)]
    n = 200

    def feed_many(datagrams, peers=False):
        src = InputSource()

        def run():
            for k in range(n):
                src.feed(datagrams[k % len(datagrams)], (f"10.0.{k // 250}.{k % 250}", 1) if peers else peer,
                         k * 1e-3)
        return run, src

    run, _ = feed_many([ten_finger])
    base = _median_cpu(run) / n
    run, src_h = feed_many([heavy])
    t_heavy = _median_cpu(run) / n
    run, src_f = feed_many(floods, peers=True)
    t_flood = _median_cpu(run) / n
    wf = src_f.work()
    # the tick's input stage: poll after 1200 one-shot senders (each: garbage + a finger)
    src_p = InputSource()
    good = ob.tuio_bundle("2Dcur", [1], ob.cursor_sets([(1, 0.5, 0.5)]), fseq=1)
    for k in range(1200):
        p = (f"10.1.{k // 250}.{k % 250}", 1)
        src_p.feed(b"garbage!", p, k * 1e-4)
        src_p.feed(good, p, k * 1e-4)
    polls = []
    for _ in range(15):
        t0 = time.process_time()
        snap = src_p.poll(0.12)
        polls.append(time.process_time() - t0)
    wp = src_p.work()
    return [
        ("feed: the heavy datagram (61 kB, 10 000 ALIVE ids + 200 SETs)", t_heavy, base,
         f"rejected before decoding; {src_h.work().arguments_decoded} arguments decoded"),
        ("feed: a flood of 200 new fingers (12 kB, 1805 arguments)", t_flood, base,
         f"{wf.contacts} contacts held (64 per source, 256 in all); the other fingers dropped and counted"),
        ("poll (the tick's input stage) after 1200 one-shot senders", statistics.median(polls), base,
         f"{len(snap.contacts)} contacts, {len(snap.health)} health records, {wp.sources_tracked} sources tracked"),
    ]


if __name__ == "__main__":
    sys.exit(main())
