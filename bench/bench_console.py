"""Benchmark: one console tick (sense, density, coverage, barrier, actuate) and the server-side scene update.

Run: ``.venv/bin/python bench/bench_console.py`` (prints a markdown table).

For N = 12, 50, 100 simulated robots running coverage (TVD-D1) on the circling density:
* ``tick``: ``ControlLoop.tick()`` (no subscribers), ms;
* ``scene``: ``ArenaScene.draw(frame)`` into a viser server with no browser connected (the
  serialisation cost every tab shares; the default layers), ms;
* ``tick + scene`` and the spare share of the 33 ms control period (target at N = 100: ≥ 30 %).
The scene runs on its own thread in the console; the sum is the one-core worst case.
Each N first runs 300 ticks (10 s) so the swarm has spread from its initial lattice.
Times are CPU time of the calling thread (``time.thread_time``: the cost on one core, robust to
other processes on a shared machine); the wall-clock median of tick + scene is shown beside.
Baseline: the same process times a fixed numpy workload (sort 10⁵ floats ×10) so machines can be compared.
"""
from __future__ import annotations

import sys
import time

import harness  # first: one BLAS thread (no thread thrash on one core), before numpy loads

from swarmdeck.core.constants import CONTROL_PERIOD


def median_ms(samples: list[float]) -> float:
    return harness.timing(samples, "thread").median_ms


def p90_ms(samples: list[float]) -> float:
    return harness.timing(samples, "thread").percentile_ms(90)


def baseline(repeats: int = 30) -> float:
    """CPU ms of a fixed numpy workload (sort 10⁵ floats ×10), to compare machines."""
    return harness.baseline(repeats).median_ms


def run(n: int, server, warm: int = 300, ticks: int = 150) -> dict[str, float]:
    from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
    from swarmdeck.console.web.scene import ArenaScene

    server.scene.reset()
    loop = ControlLoop(LoopConfig(seed=1, n_robots=n))
    scene = ArenaScene(server, loop.config.bounds)
    for _ in range(warm):
        scene.draw(loop.tick())
    tick_s, scene_s, both, wall = [], [], [], []
    stages: dict[str, list[float]] = {}
    for _ in range(ticks):
        w0 = time.perf_counter()
        c0 = time.thread_time()
        f = loop.tick()
        c1 = time.thread_time()
        scene.draw(f)
        c2 = time.thread_time()
        wall.append(time.perf_counter() - w0)
        tick_s.append(c1 - c0)
        scene_s.append(c2 - c1)
        both.append(c2 - c0)
        for k, v in f.timing.items():
            stages.setdefault(k, []).append(v)
    return {
        "tick": median_ms(tick_s), "tick_p90": p90_ms(tick_s), "scene": median_ms(scene_s),
        "scene_p90": p90_ms(scene_s), "both": median_ms(both), "both_p90": p90_ms(both), "wall": median_ms(wall),
        **{f"stage_{k}": median_ms(v) for k, v in stages.items()},
    }


def main() -> int:
    import viser

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        base0 = baseline()
        rows = [(n, run(n, server)) for n in (12, 50, 100)]
        base1 = baseline()
    finally:
        server.stop()
    base = 0.5 * (base0 + base1)
    period_ms = 1e3 * CONTROL_PERIOD
    print(f"{harness.machine()}; baseline (sort 10⁵ floats ×10) {base:.2f} ms CPU")
    print()
    print(harness.table_header(["N", "tick CPU ms (p90)", "coverage wall ms", "barrier wall ms", "scene CPU ms (p90)",
                                "tick + scene CPU ms (p90)", f"spare of {period_ms:g} ms", "wall ms",
                                "(tick+scene)/baseline"]))
    for n, r in rows:
        spare = 100.0 * (1.0 - r["both"] / period_ms)
        print(f"| {n} | {r['tick']:.2f} ({r['tick_p90']:.2f}) | {r['stage_control']:.2f} | {r['stage_safety']:.2f} | "
              f"{r['scene']:.2f} ({r['scene_p90']:.2f}) | {r['both']:.2f} ({r['both_p90']:.2f}) | {spare:.0f} % | "
              f"{r['wall']:.2f} | {r['both'] / base:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
