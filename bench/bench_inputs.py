"""Benchmark of swarmdeck.inputs: TUIO parse/assembly throughput and latency
from datagram to updated density.

    /work/venv/bin/python bench/bench_inputs.py

Prints a markdown table. Ten-finger TUIO 1.1 2Dcur bundles (source, alive, 10 set,
fseq; 784 bytes) with moving fingers. Rows: python-osc ``OscBundle`` parse alone
(the baseline, same process), ``parse_datagram`` (structural checks + python-osc),
``InputSource.feed`` (parse + TUIO assembly + calibrated contacts + events), and
``feed`` + ``poll``. Latency: ``feed`` → ``poll`` → ``ContactDensity.update`` →
``.at(t)`` per datagram. Medians over repeats of CPU time (time.process_time: the VM is shared); one thread.
"""
from __future__ import annotations

import os
import platform
import statistics
import sys
import time

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
    rates = []
    for _ in range(REPEATS):
        t0 = time.process_time()
        fn(data)
        rates.append(len(data) / (time.process_time() - t0))
    return statistics.median(rates)


def main() -> int:
    data = make_bundles(N_BUNDLES)
    peer = ("127.0.0.1", 40000)

    def python_osc(ds):
        for d in ds:
            for m in OscBundle(d):
                m.params

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

    cpu = "unknown"
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    print(f"inputs benchmark — {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
          f"nproc {os.cpu_count()}, {cpu}, Python {platform.python_version()}, "
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
    return 0


if __name__ == "__main__":
    sys.exit(main())
