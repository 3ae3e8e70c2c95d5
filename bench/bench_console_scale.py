"""The console at any size (issue 27 item 2): ticks/s at N = 1000, 3000, 5000, 10,000, CPU per stage.

Run: ``.venv/bin/python bench/bench_console_scale.py [N ...]`` (a few minutes; prints markdown rows).

Real ``ControlLoop`` ticks (simulated robots, TVD-D1 coverage on the console's moving density, the
barrier in "auto" mode) on the floors ``swarmdeck console --robots N --arena WxH`` uses: 22 × 13 m up to
N = 5000 (the issue's command), 31 × 19 m at 10,000. Two loops with the same seed tick alternately in
one process: *compiled* (today: the coverage sums in numba kernels) and *numpy* (the same loop with
``swarmdeck.coverage.kernels.AVAILABLE`` off — the code before the kernels; both give the same bits).
Per tick, process CPU time of ``loop.tick()`` and of the coverage stages inside it (pre-condition,
Voronoi, cell moments, Jacobian, law; "rest" = the tick minus these: sense, density, barrier, Frame).
ticks/s = 1 / median tick CPU (one core, no scene or recorder). Baseline: harness sort workload.
"""
from __future__ import annotations

import sys
import time
from collections import defaultdict
from contextlib import contextmanager

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

from swarmdeck.console.runtime.config import arena_bounds  # noqa: E402
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig  # noqa: E402
from swarmdeck.coverage import controller, geometry, kernels  # noqa: E402

ARENAS = {1000: "22x13", 3000: "22x13", 5000: "22x13", 10000: "31x19"}
STAGES = (("precondition", geometry, "precondition_positions"), ("voronoi", geometry, "bounded_voronoi"),
          ("moments", geometry, "cell_moments"), ("jacobian", controller, "centroid_jacobian"),
          ("law", controller, "law_command"))


@contextmanager
def stage_clock(acc: dict[str, float]):
    """Wrap the coverage stages where the tick looks them up; add each call's CPU time to ``acc``."""
    saved = [(mod, name, getattr(mod, name)) for _, mod, name in STAGES]

    def wrap(key, fn):
        def timed(*a, **k):
            t0 = time.process_time()
            try:
                return fn(*a, **k)
            finally:
                acc[key] += time.process_time() - t0
        return timed

    for (key, mod, name), (_, _, fn) in zip(STAGES, saved):
        setattr(mod, name, wrap(key, fn))
    try:
        yield
    finally:
        for mod, name, fn in saved:
            setattr(mod, name, fn)


def run(n: int, ticks: int, warm: int = 3) -> dict[str, dict[str, list[float]]]:
    loops = {v: ControlLoop(LoopConfig(n_robots=n, seed=1, bounds=arena_bounds(ARENAS[n]))) for v in ("numpy", "compiled")}
    out: dict[str, dict[str, list[float]]] = {v: defaultdict(list) for v in loops}
    for k in range(warm + ticks):
        for variant, loop in loops.items():
            acc: dict[str, float] = defaultdict(float)
            kernels.AVAILABLE = variant == "compiled" and harness_available
            with stage_clock(acc):
                t0 = time.process_time()
                loop.tick()
                total = time.process_time() - t0
            if k >= warm:
                out[variant]["tick"].append(total)
                for key, _, _ in STAGES:
                    out[variant][key].append(acc[key])
                out[variant]["rest"].append(total - sum(acc.values()))
    kernels.AVAILABLE = harness_available
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
    cols = ["N", "floor", "variant", "tick CPU ms (worst)", "ticks/s", "precondition", "voronoi", "moments",
            "jacobian", "law", "rest", "tick / numpy tick"]
    print(harness.table_header(cols))
    for n in sizes:
        ticks = 10 if n <= 5000 else 6
        res = run(n, ticks)
        ref = harness.timing(res["numpy"]["tick"], "cpu").median
        for variant in ("numpy", "compiled"):
            r = res[variant]
            tick = harness.timing(r["tick"], "cpu")
            parts = [f"{harness.timing(r[key], 'cpu').median_ms:.1f}" for key in
                     ("precondition", "voronoi", "moments", "jacobian", "law", "rest")]
            print(harness.table_row(n, ARENAS[n], variant, tick.ms(1), f"{1.0 / tick.median:.1f}", *parts,
                                    f"{tick.median / ref:.2f}"))
        sys.stdout.flush()
    delaunay_alternatives(sizes)


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [1000, 3000, 5000, 10000])
