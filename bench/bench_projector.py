"""The projector page (issue 29): frames per second drawn and tick → pixels latency in headless Chromium.

Real ``ControlLoop`` Frames (coverage on the moving density, N = 12, 100, 1000) are computed first, then handed
to a real :class:`~swarmdeck.console.projector.server.ProjectorServer` at ``--rate`` Hz (default 60, twice the
loop's 30 Hz, so the page's own limit shows) while one page (1280 × 800, every layer on, the safety discs too)
draws them. In the page: ``drawn`` (wall time after each frame's drawing, ms), ``latency`` (that time − the
server's wall time when the Frame was offered: serialisation + long poll + parse + wait for the animation frame +
drawing), ``drawMs`` (the drawing alone) and the layers it dropped to keep up. Server side: one Frame's
serialisation (``projector_message`` + JSON), ms. On a shared, loaded machine the wall-clock rate says little, so
the CPU time every process below this one (Chromium: renderer, GPU/compositor, network) and this process (the
server, the feeder, Playwright's client) spent per Frame sent is reported too, and the frames per second one idle
core could give from it.

*before / after* in the same run: ``--before REF`` (default ``a6d5fe5``, the page that drew in floor metres and
let the compositor warp the whole 1280 × 800 layer by a CSS matrix3d) serves that commit's ``projector.html`` and
``projector.js`` (``git show``, through Playwright's request routing: same server, same Frames, same browser) beside
the current page (every vertex warped in JavaScript, only the small density canvas warped by the compositor);
``--before none`` measures the current page only. ``--empty`` adds a row with every layer off (the page's own cost);
``--rounds R`` alternates before and after R times and prints the median CPU per frame (a loaded machine).

Rerun: ``.venv/bin/python bench/bench_projector.py [--before REF] [--empty] [--rounds R] [N ...]`` (≈ 2 min).
"""
from __future__ import annotations

import itertools
import subprocess
import sys
import threading
import time
from dataclasses import replace

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import msgspec
import numpy as np

from swarmdeck.console.projector.message import projector_message
from swarmdeck.console.projector.server import ProjectorServer
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.runtime.params import ProjectorParams
from swarmdeck.core.bounds import Bounds
from swarmdeck.tracking.projector import ProjectorCalibration, SyntheticProjector

CHROMIUM = "/usr/bin/chromium"
ARENAS = {12: (-1.6, 1.6, -1.0, 1.0), 100: (-1.6, 1.6, -1.0, 1.0), 1000: (-5.0, 5.0, -3.0, 3.0)}
SECONDS = 6.0
FRAMES = 40


def _descendants_cpu_s() -> float:
    """CPU time (user + system) of every process below this one (the Playwright driver and Chromium), s."""
    import os

    tick = os.sysconf("SC_CLK_TCK")
    parent: dict[int, int] = {}
    cpu: dict[int, float] = {}
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open(f"/proc/{d}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        parent[int(d)] = int(fields[1])
        cpu[int(d)] = (int(fields[11]) + int(fields[12])) / tick
    me, total = os.getpid(), 0.0
    for pid in cpu:
        p = parent.get(pid)
        while p and p != me:
            p = parent.get(p)
        if p == me:
            total += cpu[pid]
    return total


def old_page(ref: str) -> dict[str, str]:
    """``projector.html`` and ``projector.js`` as commit ``ref`` had them, by route (``git show``)."""
    def show(name: str) -> str:
        return subprocess.run(["git", "show", f"{ref}:console/projector/static/{name}"], check=True,
                              capture_output=True, text=True).stdout

    return {"**/projector": show("projector.html"), "**/projector/projector.js": show("projector.js")}


def run(n: int, browser, rate: float = 60.0, page_files: dict[str, str] | None = None,
        empty: bool = False, off: tuple[str, ...] = ()) -> dict:
    b = Bounds.of(ARENAS[n])
    loop = ControlLoop(LoopConfig(n_robots=n, bounds=b, seed=1))
    frames = [loop.tick() for _ in range(FRAMES)]
    loop.close()
    settings = (ProjectorParams(density=False, cells=False, centroids=False, goals=False, halos=False, graph=False,
                                annotations=False) if empty else ProjectorParams(safety=True))
    settings = replace(settings, **{layer: False for layer in off})
    ser = harness.measure(lambda: msgspec.json.encode(projector_message(frames[-1], 1, settings, 0.0)), 15,
                          clock="thread")  # what the server does once per Frame
    m = 0.05 * max(b.width, b.height)
    proj = SyntheticProjector(view_bounds=(b.x_min - m, b.x_max + m, b.y_min - m, b.y_max + m))
    srv = ProjectorServer(b, ProjectorCalibration(proj.homography(), proj.size, b), port=0, settings=settings).start()
    page = browser.new_page(viewport={"width": proj.width, "height": proj.height})
    for pattern, body in (page_files or {}).items():
        kind = "text/html" if pattern.endswith("/projector") else "text/javascript"
        page.route(pattern, lambda route, *_, body=body, kind=kind: route.fulfill(body=body, content_type=kind))
    page.goto(srv.url)
    page.wait_for_function("window.swarmdeckProjector && window.swarmdeckProjector.connected", timeout=30000)
    stop = threading.Event()

    def feed() -> None:
        k = 0
        while not stop.is_set():
            srv.offer(frames[k % len(frames)])
            k += 1
            time.sleep(1.0 / rate)

    t = threading.Thread(target=feed, daemon=True)
    t.start()
    time.sleep(1.0)  # warm-up
    page.evaluate("(() => { const s = window.swarmdeckProjector; s.drawn = []; s.latency = []; s.drawMs = []; })()")
    cpu0, own0, sent0 = _descendants_cpu_s(), time.process_time(), srv.state()["sent"]
    time.sleep(SECONDS)
    cpu1, own1, sent1 = _descendants_cpu_s(), time.process_time(), srv.state()["sent"]
    st = page.evaluate("(() => { const s = window.swarmdeckProjector; return {drawn: s.drawn, latency: s.latency, "
                       "drawMs: s.drawMs, dropped: s.dropped}; })()")
    stop.set()
    t.join()
    state = srv.state()
    page.close()
    srv.close()
    drawn = np.asarray(st["drawn"])
    fps = (len(drawn) - 1) / ((drawn[-1] - drawn[0]) / 1000.0) if len(drawn) > 1 else 0.0
    lat = np.asarray(st["latency"])
    return {"n": n, "fps": fps, "lat_med": float(np.median(lat)), "lat_p95": float(np.percentile(lat, 95)),
            "draw_med": float(np.median(st["drawMs"])), "draw_max": float(np.max(st["drawMs"])),
            "ser": ser.median_ms, "dropped": ",".join(st["dropped"]) or "none", "skipped": state["skipped"],
            "sent": state["sent"],
            "browser_cpu": 1000.0 * (cpu1 - cpu0) / max(sent1 - sent0, 1),
            "server_cpu": 1000.0 * (own1 - own0) / max(sent1 - sent0, 1)}


def main(argv: list[str]) -> int:
    from playwright.sync_api import sync_playwright

    before, empty, rounds = "a6d5fe5", False, 1
    if "--rounds" in argv:  # before and after alternated R times (a loaded machine: compare medians)
        k = argv.index("--rounds")
        rounds = int(argv[k + 1])
        argv = argv[:k] + argv[k + 2:]
    if "--before" in argv:
        k = argv.index("--before")
        before = argv[k + 1]
        argv = argv[:k] + argv[k + 2:]
    if "--empty" in argv:
        empty = True
        argv = [a for a in argv if a != "--empty"]
    ns = [int(a) for a in argv] or [12, 100, 1000]
    pages: list[tuple[str, dict[str, str] | None]] = [("after", None)]
    if before != "none":
        pages.insert(0, (f"before ({before})", old_page(before)))
    print(harness.machine())
    print("| page | N | page frames/s | tick → pixels ms, median (p95) | drawing ms, median (max) | serialisation ms | "
          "CPU ms per frame: browser + server | frames/s one core could give | layers dropped | frames sent / skipped |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- | ---: |")
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        try:
            cases = [(n, False) for n in ns] + ([(ns[0], True)] if empty else [])
            cpu: dict[tuple[str, int], list[float]] = {}
            for (n, blank), _, (name, files) in itertools.product(cases, range(rounds), pages):
                r = run(n, browser, page_files=files, empty=blank)
                label = name + (" (every layer off)" if blank else "")
                cpu.setdefault((label, n), []).append(r["browser_cpu"] + r["server_cpu"])
                print(f"| {label} | {r['n']} | {r['fps']:.1f} | {r['lat_med']:.1f} ({r['lat_p95']:.1f}) | "
                      f"{r['draw_med']:.2f} ({r['draw_max']:.1f}) | {r['ser']:.2f} | "
                      f"{r['browser_cpu']:.1f} + {r['server_cpu']:.1f} | "
                      f"{1000.0 / (r['browser_cpu'] + r['server_cpu']):.0f} | {r['dropped']} | "
                      f"{r['sent']} / {r['skipped']} |", flush=True)
            if rounds > 1:
                for (label, n), v in cpu.items():
                    print(f"{label}, N = {n}: CPU ms per frame over {len(v)} rounds, median {np.median(v):.1f} "
                          f"(min {min(v):.1f}) → {1000.0 / np.median(v):.0f} frames/s on one core")
        finally:
            browser.close()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
