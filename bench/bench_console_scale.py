"""The console at any size (issue 27 item 2): ticks/s at N = 1000, 3000, 5000, 10,000, CPU per stage.

Run: ``.venv/bin/python bench/bench_console_scale.py [N ...]`` (a few minutes; prints markdown rows).

Real ``ControlLoop`` ticks (simulated robots, TVD-D1 coverage on the console's moving density, the
barrier in "auto" mode) on the floors ``swarmdeck console --robots N --arena WxH`` uses: 22 × 13 m up to
N = 5000 (the issue's command), 31 × 19 m at 10,000. Three loops with the same seed tick alternately in
one process: *numpy* (``coverage_worker="off"`` and ``swarmdeck.coverage.kernels.AVAILABLE`` off: the
coverage sums before the kernels), *sync* (``coverage_worker="off"``: every stage on the loop thread,
the console below 2000 robots) and *worker* (``coverage_worker="on"``: coverage one tick behind on its
worker thread, the console's default from 2000 robots). Per tick: the loop thread's CPU time of
``loop.tick()`` (*loop*), the coverage stages' CPU time on whichever thread ran them (pre-condition,
Voronoi, cell moments, Jacobian, law; *rest* = the loop thread's tick minus the stages it ran itself:
sense, density, barrier, Frame) and, for *worker*, the worker thread's CPU (*worker* = process CPU −
loop thread CPU from the tick's start until the worker's step of this tick's inputs is done). ticks/s (2 cores) = 1 / max(loop, worker) medians: what the tick holds
when each thread has a core (sync: 1 / loop, one core); the wall ticks/s of the back-to-back ticks is
printed too (meaningful only on an idle machine). No scene or recorder. Baseline: harness sort workload.

The console's own rate, for a quiet machine (the issue's "done when": ``swarmdeck console --robots 5000 --arena
22x13`` holds 10 ticks/s by the wall clock):

- ``bench_console_scale.py --alone [N ...]``: ONE loop in the console's configuration (``coverage_worker="auto"``:
  two workers from 2000 robots), ticking back to back, nothing interleaved: wall ticks/s, process CPU per tick
  (all threads) and the loop thread's CPU, medians (worst) over 40 ticks after 5 warm-up (20 at 10,000).
- ``bench_console_scale.py --console [N ...]``: the real ``swarmdeck console --robots N --arena WxH --no-record``
  in a child process, run for 10 s and for 40 s (``--duration``); its tick counter ("ran K ticks") gives
  ticks/s = (K40 − K10) / 30 s by the wall clock, start-up (imports, kernel loads, first tick) cancelled out.
"""
from __future__ import annotations

import sys
import time
from collections import defaultdict
from contextlib import contextmanager

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

from swarmdeck.console.runtime.config import arena_bounds  # noqa: E402
from swarmdeck.console.runtime.coverage_worker import PipelinedCoverage  # noqa: E402
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig  # noqa: E402
from swarmdeck.console.runtime.params import BehaviourParams, SafetyParams  # noqa: E402
from swarmdeck.coverage import controller, geometry, kernels  # noqa: E402

ARENAS = {1000: "22x13", 3000: "22x13", 5000: "22x13", 10000: "31x19"}
STAGES = (("precondition", geometry, "precondition_positions"), ("voronoi", geometry, "bounded_voronoi"),
          ("moments", geometry, "cell_moments"), ("jacobian", controller, "centroid_jacobian"),
          ("law", controller, "law_command"))
VARIANTS = {"numpy": "off", "sync": "off", "worker": "on", "worker2": "on"}


@contextmanager
def stage_clock(acc: dict[str, float], own: dict[str, float]):
    """Wrap the coverage stages where the tick looks them up; add each call's CPU time (of the thread
    running it) to ``acc``, and to ``own`` when that thread is the caller's."""
    saved = [(mod, name, getattr(mod, name)) for _, mod, name in STAGES]
    import threading

    me = threading.get_ident()

    def wrap(key, fn):
        def timed(*a, **k):
            t0 = time.thread_time()
            try:
                return fn(*a, **k)
            finally:
                dt = time.thread_time() - t0
                acc[key] += dt
                if threading.get_ident() == me:
                    own[key] += dt
        return timed

    for (key, mod, name), (_, _, fn) in zip(STAGES, saved):
        setattr(mod, name, wrap(key, fn))
    try:
        yield
    finally:
        for mod, name, fn in saved:
            setattr(mod, name, fn)


def run(n: int, ticks: int, warm: int = 3) -> dict[str, dict[str, list[float]]]:
    loops = {v: ControlLoop(LoopConfig(n_robots=n, seed=1, bounds=arena_bounds(ARENAS[n]), coverage_worker=w))
             for v, w in VARIANTS.items()}
    loops["worker2"].use_behaviour(PipelinedCoverage(BehaviourParams(), arena_bounds(ARENAS[n]), LoopConfig().max_speed,
                                                     SafetyParams().safety_distance, depth=2))
    out: dict[str, dict[str, list[float]]] = {v: defaultdict(list) for v in loops}
    try:
        for k in range(warm + ticks):
            for variant, loop in loops.items():
                acc: dict[str, float] = defaultdict(float)
                own: dict[str, float] = defaultdict(float)
                kernels.AVAILABLE = variant != "numpy" and harness_available
                with stage_clock(acc, own):
                    w0, c0, p0 = time.perf_counter(), time.thread_time(), time.process_time()
                    loop.tick()
                    queue = getattr(loop._behaviour, "_queue", None)
                    for pending in list(queue or ()):  # the workers' steps of this tick's inputs: in this tick
                        pending.result(timeout=600)
                    wall = time.perf_counter() - w0
                    total = time.thread_time() - c0
                    proc = time.process_time() - p0
                if k >= warm:
                    out[variant]["tick"].append(total)
                    out[variant]["wall"].append(wall)
                    out[variant]["worker"].append(max(proc - total, 0.0) if variant.startswith("worker") else 0.0)
                    for key, _, _ in STAGES:
                        out[variant][key].append(acc[key])
                    out[variant]["rest"].append(total - sum(own.values()))
    finally:
        kernels.AVAILABLE = harness_available
        for loop in loops.values():
            loop.close()
    return out


harness_available = kernels.AVAILABLE


def delaunay_alternatives(sizes: list[int]) -> None:
    """The Voronoi stage's triangulation: scipy's qhull (used) against GEOS (shapely), thread CPU, on
    the N robots plus the ≈ 11 % reflections the console's floors need."""
    import numpy as np
    import shapely
    from scipy.spatial import Delaunay

    rng = np.random.default_rng(1)
    print(harness.table_header(["N", "qhull Delaunay ms (worst)", "GEOS delaunay_triangles ms (worst)"]))
    for n in sizes:
        p = rng.uniform([0.0, 0.0], [22.0, 13.0], (int(1.11 * n), 2))
        mp = shapely.multipoints(p)
        a = harness.measure(lambda p=p: Delaunay(p), 7, clock="thread", warmup=1)
        b = harness.measure(lambda mp=mp: shapely.delaunay_triangles(mp), 7, clock="thread", warmup=1)
        print(harness.table_row(n, a.ms(1), b.ms(1)))


def main(sizes: list[int]) -> None:
    print(harness.machine())
    print("baseline (sort 1e5 ×10, thread CPU):", harness.baseline().ms())
    cols = ["N", "floor", "variant", "loop CPU ms (worst)", "worker CPU ms", "ticks/s (2 cores)", "wall ticks/s",
            "precondition", "voronoi", "moments", "jacobian", "law", "rest", "ticks/s / sync"]
    print(harness.table_header(cols))
    for n in sizes:
        ticks = 10 if n <= 5000 else 6
        res = run(n, ticks)
        med = {v: harness.timing(res[v]["tick"], "cpu").median for v in res}
        rate = {}
        for v in res:
            worker = harness.timing(res[v]["worker"], "cpu").median
            if v == "worker2":  # two workers: the diagram (pre-condition, Voronoi) and the rest; two cores
                a = sum(harness.timing(res[v][key], "cpu").median for key in ("precondition", "voronoi"))
                rate[v] = 1.0 / max(med[v], a, worker - a, 0.5 * (med[v] + worker))
            else:
                rate[v] = 1.0 / max(med[v], worker)
        for variant in VARIANTS:
            r = res[variant]
            tick = harness.timing(r["tick"], "cpu")
            parts = [f"{harness.timing(r[key], 'cpu').median_ms:.1f}" for key in
                     ("precondition", "voronoi", "moments", "jacobian", "law", "rest")]
            worker = harness.timing(r["worker"], "cpu").median_ms
            wall = harness.timing(r["wall"], "wall").median
            print(harness.table_row(n, ARENAS[n], variant, tick.ms(1), f"{worker:.1f}", f"{rate[variant]:.1f}",
                                    f"{1.0 / wall:.1f}", *parts, f"{rate[variant] / rate['sync']:.2f}"))
        sys.stdout.flush()
    delaunay_alternatives(sizes)


def alone(sizes: list[int]) -> None:
    """One loop in the console's configuration, back to back (module docstring, ``--alone``)."""

    print(harness.machine())
    print(harness.table_header(["N", "floor", "wall ticks/s", "wall ms/tick (worst)", "process CPU ms/tick (worst)",
                                "loop thread CPU ms (worst)"]))
    for n in sizes:
        warm, ticks = 5, (40 if n <= 5000 else 20)
        loop = ControlLoop(LoopConfig(n_robots=n, seed=1, bounds=arena_bounds(ARENAS[n]), coverage_worker="auto"))
        wall, proc, own = [], [], []
        try:
            for _ in range(warm):
                loop.tick()
            t_start = time.perf_counter()
            for _ in range(ticks):
                w0, p0, c0 = time.perf_counter(), time.process_time(), time.thread_time()
                loop.tick()
                wall.append(time.perf_counter() - w0)
                proc.append(time.process_time() - p0)
                own.append(time.thread_time() - c0)
            span = time.perf_counter() - t_start
        finally:
            loop.close()
        print(harness.table_row(n, ARENAS[n], f"{ticks / span:.1f}", harness.timing(wall, "wall").ms(1),
                                harness.timing(proc, "cpu").ms(1), harness.timing(own, "cpu").ms(1)))
        sys.stdout.flush()


def console(sizes: list[int], short: float = 10.0, long: float = 40.0) -> None:
    """The real ``swarmdeck console`` in a child process; ticks/s from its tick counter (``--console``)."""
    import re
    import subprocess

    def ticks(n: int, duration: float) -> int:
        argv = [*harness.swarmdeck_cli(), "console", "--robots", str(n), "--arena", ARENAS[n], "--port", "0",
                "--no-record", "--duration", f"{duration:g}"]
        done = subprocess.run(argv, capture_output=True, text=True, timeout=duration + 600, check=False)
        found = re.search(r"ran (\d+) ticks", done.stdout)
        if done.returncode != 0 or found is None:
            raise RuntimeError(f"swarmdeck console exited {done.returncode}: {done.stderr[-2000:]}")
        return int(found.group(1))

    print(harness.machine())
    print(harness.table_header(["N", "floor", f"ticks in {short:g} s", f"ticks in {long:g} s",
                                "console ticks/s (wall)"]))
    for n in sizes:
        k_short, k_long = ticks(n, short), ticks(n, long)
        print(harness.table_row(n, ARENAS[n], k_short, k_long, f"{(k_long - k_short) / (long - short):.1f}"))
        sys.stdout.flush()


if __name__ == "__main__":
    args = sys.argv[1:]
    mode = args.pop(0) if args and args[0] in ("--alone", "--console") else None
    chosen = [int(a) for a in args]
    if mode == "--alone":
        alone(chosen or [5000])
    elif mode == "--console":
        console(chosen or [5000])
    else:
        main(chosen or [1000, 3000, 5000, 10000])
