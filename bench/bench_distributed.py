"""Benchmark of the distributed barrier (issue 18 item 2): per-robot QPs vs the centralised QP.

Run: ``.venv/bin/python bench/bench_distributed.py [--quick] [--sizes 100,1000]`` (BLAS pinned to one thread).

Same dense random scenes as ``bench_safety.py`` (REFERENCE.md §3: a random 80 % of a
jittered grid of pitch 0.188 m, random nominal directions, speeds U(0, v_max); N ≤ 100
in the 3.2 × 2.0 m arena, larger arenas of the same aspect and occupancy beyond).
Per scene, in the same process, times in process CPU ms (robust to other load):

* *distributed cold*: a fresh ``SafetyFilter(mode="distributed")`` call (rows, split,
  per-robot enumeration, certificate, diagnostics);
* *clarabel cold*: ``SafetyFilter(solver="clarabel")``, the same pruned rows solved by
  clarabel (the issue's baseline), and *centralised cold* with the default solver;
* *closed loop*: 20 ticks x ← x + u·dt with drifting nominals, ticks 2–20, for the
  distributed filter and the centralised default (decides "auto"'s threshold: the
  robot count where the centralised filter stops fitting a 33 ms tick with room for
  the rest of the loop);
* *invasiveness*: Σ‖u − û‖² of the distributed answer over that of the centralised
  optimum (clarabel) on the same scene (≥ 1: the halves are more conservative);
* violated pair rows: centralised rows the distributed answers violate by > 1e-9 m/s.
"""
from __future__ import annotations

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import os
import platform  # noqa: E402
import time  # noqa: E402

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np  # noqa: E402

from swarmdeck.safety import BarrierConfig, SafetyFilter  # noqa: E402
from swarmdeck.safety.constraints import barrier_rows  # noqa: E402
from swarmdeck.safety.scenes import arena_for, grid_scene  # noqa: E402

PITCH = 0.188


def config_for(n: int) -> BarrierConfig:
    return BarrierConfig() if n <= 100 else BarrierConfig(bounds=arena_for(n, PITCH, fill=0.8))


timed = harness.timed  # (process CPU seconds, result)


def closed_loop(cfg: BarrierConfig, x: np.ndarray, nominal: np.ndarray, ticks: int, seed: int) -> list[float]:
    rng = np.random.default_rng(seed)
    f = SafetyFilter(cfg)
    ang = np.arctan2(nominal[:, 1], nominal[:, 0])
    speed = np.linalg.norm(nominal, axis=1)
    out = []
    for k in range(ticks):
        nom = np.stack([np.cos(ang), np.sin(ang)], axis=1) * speed[:, None]
        t, (u, diag) = timed(f.filter, x, nom)
        assert diag.ok, diag.status
        if k:
            out.append(t)
        x = x + u * cfg.dt
        ang = ang + rng.normal(0, 0.1, x.shape[0])
    return out


def bench(n: int, scenes: int, ticks: int, rng: np.random.Generator) -> dict:
    cfg = config_for(n)
    dist_cfg = dataclasses.replace(cfg, mode="distributed")
    r = {k: [] for k in ("dist", "clar", "cent", "dist_loop", "cent_loop", "inv")}
    violated = 0
    for s in range(scenes):
        x, nominal = grid_scene(n, rng, cfg, pitch=PITCH)
        t, (ud, dd) = timed(SafetyFilter(dist_cfg).filter, x, nominal)
        assert dd.ok, dd.status
        r["dist"].append(t)
        t, (uc, dc) = timed(SafetyFilter(dataclasses.replace(cfg, solver="clarabel")).filter, x, nominal)
        assert dc.ok, dc.status
        r["clar"].append(t)
        t, _ = timed(SafetyFilter(cfg).filter, x, nominal)
        r["cent"].append(t)
        rows = barrier_rows(x, cfg)
        violated += int(np.sum(rows.lhs(ud) > rows.b + 1e-9))
        r["inv"].append(float(np.sum((ud - nominal) ** 2) / max(np.sum((uc - nominal) ** 2), 1e-300)))
        r["dist_loop"] += closed_loop(dist_cfg, x, nominal, ticks, s)
        r["cent_loop"] += closed_loop(cfg, x, nominal, ticks, s)
    med = {k: float(np.median(v)) for k, v in r.items()}
    return dict(n=n, arena=cfg.bounds, violated=violated, **med)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer scenes")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--sizes", type=lambda v: {int(x) for x in v.split(",")}, default=None,
                    help="only these robot counts, e.g. 100,1000")
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
    print(f"# bench_distributed  {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}  nproc={os.cpu_count()}  "
          f"cpu={cpu}  python={platform.python_version()}  load={os.getloadavg()[0]:.1f}\n")
    print("| N | arena (m) | distributed cold ms | clarabel cold ms | ratio clarabel / distributed | "
          "centralised (default) cold ms | distributed closed-loop ms | centralised closed-loop ms | "
          "invasiveness distributed / optimum | violated pair rows |")
    print("| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    plan = [(20, 20, 20), (100, 10, 20), (200, 6, 20), (300, 5, 20), (500, 4, 20), (1000, 8, 20)]
    for n, scenes, ticks in plan:
        if args.sizes is not None and n not in args.sizes:
            continue
        if args.quick:
            scenes = max(1, scenes // 3)
        r = bench(n, scenes, ticks, rng)
        x0, x1, y0, y1 = r["arena"]
        print(f"| {n} | {x1 - x0:.1f} × {y1 - y0:.1f} | {1e3 * r['dist']:.2f} | {1e3 * r['clar']:.1f} | "
              f"{r['clar'] / r['dist']:.1f} | {1e3 * r['cent']:.1f} | {1e3 * r['dist_loop']:.2f} | "
              f"{1e3 * r['cent_loop']:.1f} | {r['inv']:.2f} | {r['violated']} |", flush=True)


if __name__ == "__main__":
    main()
