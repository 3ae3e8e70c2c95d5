"""Distributed barrier (issue 27 item 1): cost/optimum and CPU time against the consensus passes K, compiled.

Run: ``.venv/bin/python bench/bench_distributed_consensus.py [--n 100 200 1000 5000] [--ticks 60] [--every 3]``
(≈ 10 min idle with the defaults; BLAS pinned to one thread).

Scene: the dense crossing (``safety.scenes.crossing_scene``, as ``bench_barrier_anytime.py``): N robots
swap through the centre of a half-filled floor and jam there. The trajectory follows the default distributed
filter (K = 0); on every ``--every``-th tick after the first, on the same points and nominal (so the same rows),
each filter below is called once and timed in process CPU time (``time.process_time``, one thread, one process,
so the ratios hold under the machine's load):

* *distributed 1 pass*: the half/half split only (``distributed_second_pass=False``);
* *distributed K = k*: the default two passes (half/half, then ``reallocate_halves``) and k consensus passes
  (``distributed_consensus_passes``: each pair's remaining slack shared equally at the last answer);
* *distributed K = 2, numpy*: K = 2 with the per-robot QPs on the numpy path (the speed-up of the kernel);
* *clarabel*: a fresh ``solver="clarabel"`` filter on the same rows (the optimum: its cost is the denominator);
* *centralised*: the default exact filter, warm (N ≤ 1000 only: seconds per tick beyond).

Cost/optimum: Σ‖u − û‖² of each answer over clarabel's, over ticks where the optimum intervenes (mean and
worst); every answer's certificate is checked (``diag.ok``) and its worst row excess printed.
"""
from __future__ import annotations

import argparse  # noqa: E402
import collections  # noqa: E402
import dataclasses  # noqa: E402

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np  # noqa: E402

from swarmdeck.safety import SafetyFilter, distributed  # noqa: E402
from swarmdeck.safety.constraints import barrier_rows  # noqa: E402
from swarmdeck.safety.scenes import crossing_scene, toward  # noqa: E402

PASSES = (0, 1, 2, 4, 8)


timed = harness.timed  # (process CPU s, result)


class NumpyPath:
    """A filter whose per-robot QPs run on ``solve_small_qps``'s numpy path (the kernel switched off for the call)."""

    def __init__(self, flt: SafetyFilter) -> None:
        self.flt = flt

    def filter(self, x: np.ndarray, nom: np.ndarray):
        distributed._COMPILED = False
        try:
            return self.flt.filter(x, nom)
        finally:
            distributed._COMPILED = True


def run(n: int, ticks: int, every: int) -> dict:
    cfg, x, goals = crossing_scene(n, np.random.default_rng(0))
    dist = dataclasses.replace(cfg, mode="distributed")
    filters = {"distributed 1 pass": SafetyFilter(dataclasses.replace(dist, distributed_second_pass=False))}
    for k in PASSES:
        filters[f"distributed K = {k}"] = SafetyFilter(dataclasses.replace(dist, distributed_consensus_passes=k))
    filters["distributed K = 2, numpy"] = NumpyPath(SafetyFilter(dataclasses.replace(dist, distributed_consensus_passes=2)))
    if n <= 1000:
        filters["centralised"] = SafetyFilter(dataclasses.replace(cfg, mode="centralised"))
    clar = dataclasses.replace(cfg, solver="clarabel")
    drive = SafetyFilter(dist)
    times, cost = collections.defaultdict(list), collections.defaultdict(list)
    excess = collections.defaultdict(float)
    for tick in range(ticks):
        nom = toward(goals, x, cfg.max_speed)
        if tick and tick % every == 0:
            rows = barrier_rows(x, cfg)
            out = {}
            for name, flt in filters.items():
                t, (u, d) = timed(flt.filter, x, nom)
                assert d.ok, (name, d.status)
                times[name].append(t)
                out[name] = u
                excess[name] = max(excess[name], float(np.max(rows.lhs(u) - rows.b, initial=-np.inf)))
            t, (u_opt, d) = timed(SafetyFilter(clar).filter, x, nom)
            assert d.ok, d.status
            times["clarabel"].append(t)
            c_opt = float(np.sum((u_opt - nom) ** 2))
            if c_opt > 1e-12:
                for name, u in out.items():
                    cost[name].append(float(np.sum((u - nom) ** 2)) / c_opt)
        u, d = drive.filter(x, nom)
        assert d.ok, d.status
        x = x + u * cfg.dt
    return dict(times=times, cost=cost, excess=excess)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[100, 200, 1000, 5000])
    ap.add_argument("--ticks", type=int, default=60)
    ap.add_argument("--every", type=int, default=3, help="measure every this many ticks of the trajectory")
    args = ap.parse_args()
    print(harness.machine())
    print("| N | filter | median ms | worst ms | mean cost / optimum | worst cost / optimum | worst row excess m/s |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for n in args.n:
        r = run(n, args.ticks, args.every)
        for name, v in r["times"].items():
            c = r["cost"].get(name, [])
            e = r["excess"].get(name)
            print(f"| {n} | {name} | {1e3 * np.median(v):.2f} | {1e3 * max(v):.2f} | "
                  + (f"{np.mean(c):.3f} | {max(c):.3f} |" if c else "1 (the optimum) | – |")
                  + (f" {e:.1e} |" if e is not None else " – |"), flush=True)


if __name__ == "__main__":
    main()
