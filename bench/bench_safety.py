"""Benchmark of the safety filter (issue 4): median ms per call on dense random scenes.

Run: ``.venv/bin/python bench/bench_safety.py [--quick]`` (BLAS pinned to one thread by the harness)
(BLAS threads are pinned to one below as well, before numpy is imported).

Scenes (REFERENCE.md §3): robots on a random subset (80 % occupancy) of a
jittered grid of pitch 0.188 m (D_s + 0.018 m), every pair ≥ D_s + 0.01 m apart,
random nominal directions and speeds up to v_max. N ≤ 100 in the default
3.2 × 2.0 m arena; N ≥ 200 in a larger arena of the same aspect and occupancy
(200 robots do not fit the default arena at that pitch).

Times are process CPU time (one thread; robust to other load on a shared VM).
Columns: *cold* = a fresh filter per scene (no warm start); *closed loop* = the
same filter over 20 consecutive ticks (x ← x + u·dt, nominal directions
drifting), median over ticks 2…20 (warm-started active set); *pruned clarabel*
= the same pruned rows solved by clarabel every call (``solver="clarabel"``);
*all pairs* = the plain dense formulation (``safety.reference``), the in-process
baseline; ratio = all pairs / cold.

``--closed-loop``: issue 18 item 1 only — the warm-started filter over a closed loop against,
on every tick, cold clarabel on the same pruned rows and a cold exact solve (same process), and
a second closed-loop filter without the dual-ascent prediction (``warm_dual_sweeps=0``).
"""
from __future__ import annotations

import argparse  # noqa: E402
import collections  # noqa: E402
import dataclasses  # noqa: E402
import os
import platform  # noqa: E402
import time  # noqa: E402

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np  # noqa: E402

from swarmdeck.safety import BarrierConfig, SafetyFilter  # noqa: E402
from swarmdeck.safety.reference import all_pairs_filter  # noqa: E402
from swarmdeck.safety.scenes import arena_for, grid_scene  # noqa: E402

PITCH = 0.188


def config_for(n: int) -> BarrierConfig:
    if n <= 100:
        return BarrierConfig()
    return BarrierConfig(bounds=arena_for(n, PITCH, fill=0.8))


timed = harness.timed  # (process CPU seconds, result)


def bench(n: int, scenes: int, ticks: int, baseline: bool, rng: np.random.Generator) -> dict:
    cfg = config_for(n)
    cold, loop, pruned, dense = [], [], [], []
    methods = collections.Counter()
    fails = 0
    for _ in range(scenes):
        x, nominal = grid_scene(n, rng, cfg, pitch=PITCH)
        t, (u, diag) = timed(SafetyFilter(cfg).filter, x, nominal)
        cold.append(t)
        methods[diag.method] += 1
        fails += not diag.ok
        t, (_, d2) = timed(SafetyFilter(dataclasses.replace(cfg, solver="clarabel")).filter, x, nominal)
        pruned.append(t)
        if baseline:
            t, res = timed(all_pairs_filter, x, nominal, cfg)
            dense.append(t)
            assert res.ok and diag.ok and np.abs(res.u - u).max() < 1e-5, "filter disagrees with the baseline"
        f = SafetyFilter(cfg)
        ang = np.arctan2(nominal[:, 1], nominal[:, 0])
        speed = np.linalg.norm(nominal, axis=1)
        for k in range(ticks):
            nom = np.stack([np.cos(ang), np.sin(ang)], axis=1) * speed[:, None]
            t, (u, diag) = timed(f.filter, x, nom)
            if k:
                loop.append(t)
            fails += not diag.ok
            x = x + u * cfg.dt
            ang = ang + rng.normal(0, 0.1, n)
    def med(v):
        return 1e3 * float(np.median(v)) if v else float("nan")

    return dict(n=n, cold=med(cold), loop=med(loop), pruned=med(pruned), dense=med(dense),
                methods=dict(methods), fails=fails, arena=cfg.bounds)


def closed_loop(n: int, ticks: int, rng: np.random.Generator) -> dict:
    """Issue 18 item 1: one filter over ``ticks`` closed-loop ticks (warm-started) against, on
    every tick's same points and nominal, cold clarabel on the same pruned rows
    (``solver="clarabel"``, fresh filter) and a cold exact solve (fresh ``"auto"`` filter)."""
    cfg = config_for(n)
    x, nominal = grid_scene(n, rng, cfg, pitch=PITCH)
    ang = np.arctan2(nominal[:, 1], nominal[:, 0])
    speed = np.linalg.norm(nominal, axis=1)
    warm = SafetyFilter(cfg)
    no_dual = SafetyFilter(dataclasses.replace(cfg, warm_dual_sweeps=0))  # the warm paths before the ascent
    t_warm, t_clarabel, t_cold, t_no_dual, diff = [], [], [], [], 0.0
    methods = collections.Counter()
    for k in range(ticks):
        nom = np.stack([np.cos(ang), np.sin(ang)], axis=1) * speed[:, None]
        t, (u, diag) = timed(warm.filter, x, nom)
        tc, (_, dc) = timed(SafetyFilter(dataclasses.replace(cfg, solver="clarabel")).filter, x, nom)
        te, (ue, de) = timed(SafetyFilter(cfg).filter, x, nom)
        tn, (un, dn) = timed(no_dual.filter, x, nom)
        assert diag.ok and dc.ok and de.ok and dn.ok, (diag.status, dc.status, de.status, dn.status)
        if k:  # tick 0 is a cold start for every filter
            t_warm.append(t)
            t_clarabel.append(tc)
            t_cold.append(te)
            t_no_dual.append(tn)
            methods[diag.method] += 1
            diff = max(diff, float(np.abs(u - ue).max()), float(np.abs(un - ue).max()))
        x = x + u * cfg.dt
        ang = ang + rng.normal(0, 0.1, n)
    def med(v):
        return 1e3 * float(np.median(v))

    return dict(n=n, warm=med(t_warm), clarabel=med(t_clarabel), cold=med(t_cold), no_dual=med(t_no_dual), diff=diff,
                methods=dict(methods))


def main_closed_loop(args: argparse.Namespace, rng: np.random.Generator) -> None:
    print("| N | closed-loop ms (warm) | cold clarabel, same rows, ms | cold exact (auto) ms | "
          "warm without the dual ascent ms | ratio clarabel / warm | max ‖warm − cold‖ m/s | closed-loop methods |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for n, ticks in ((20, 60), (100, 60), (200, 40), (500, 20), (1000, 12)):
        if args.quick:
            ticks = max(6, ticks // 3)
        r = closed_loop(n, ticks, rng)
        methods = ", ".join(f"{k} {v}" for k, v in sorted(r["methods"].items()))
        print(f"| {n} | {r['warm']:.2f} | {r['clarabel']:.2f} | {r['cold']:.2f} | {r['no_dual']:.2f} | "
              f"{r['clarabel'] / r['warm']:.2f} | {r['diff']:.1e} | {methods} |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer scenes")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--closed-loop", action="store_true",
                    help="only the closed-loop warm start against cold clarabel (issue 18 item 1)")
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
    print(f"# bench_safety  {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}  nproc={os.cpu_count()}  "
          f"cpu={cpu}  python={platform.python_version()}  load={os.getloadavg()[0]:.1f}\n")
    if args.closed_loop:
        main_closed_loop(args, rng)
        return
    print("| N | arena (m) | cold ms | closed-loop ms | pruned clarabel ms | all pairs ms | ratio all pairs / cold | cold methods |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    plan = [(10, 40, 20, True), (20, 40, 20, True), (50, 30, 20, True), (100, 20, 20, True),
            (200, 10, 20, True), (500, 5, 20, False), (1000, 3, 20, False)]
    for n, scenes, ticks, baseline in plan:
        if args.quick:
            scenes = max(2, scenes // 4)
        r = bench(n, scenes, ticks, baseline, rng)
        x_min, x_max, y_min, y_max = r["arena"]
        ratio = r["dense"] / r["cold"] if baseline else float("nan")
        methods = ", ".join(f"{k} {v}" for k, v in sorted(r["methods"].items()))
        failed = f" ({r['fails']} FAILED)" if r["fails"] else ""
        print(f"| {n} | {x_max - x_min:.1f} × {y_max - y_min:.1f} | {r['cold']:.2f} | {r['loop']:.2f} | "
              f"{r['pruned']:.2f} | {r['dense']:.1f} | {ratio:.1f} | "
              f"{methods}{failed} |", flush=True)


if __name__ == "__main__":
    main()
