"""Barrier closed loop, dense crossing (issue 27 item 1): worst and median tick per mode, same rows.

Run: ``.venv/bin/python bench/bench_barrier_anytime.py [--n 100 1000] [--ticks 120]`` (≈ 10 min at
N = 1000 on a loaded 2-core machine; BLAS threads pinned to one below);
``... --cold [20 100 1000] [--scenes 30]``: single cold calls instead (see ``cold`` below).

Scene: N robots on a jittered grid filling half of the floor's central disc, each driven by a
proportional controller (gain 1, capped at v_max) to its point reflected through the centre: the
swarm swaps through the centre, so the middle jams. The trajectory follows the anytime filter
(``mode="anytime"``); on every tick, on the same points and nominal (so the same rows), each
filter below is called once and timed (process CPU time, ``time.process_time``, one thread; the
same process, so ratios hold under the machine's load):

* *centralised*: today's warm-started exact filter (``mode="centralised"``, no caps);
* *warm-capped*: the same with ``active_set_max_solves`` (the warm paths stop and go to clarabel cold);
* *anytime, fixed caps*: ``mode="anytime"`` with the pipelines' caps before ``warm_share`` (clarabel
  cold after 12 active-set factorisations, the distributed floor after 120);
* *anytime*: ``mode="anytime"`` with the pipelines' settings (``safety.config.pipeline_defaults``:
  the same caps, each active-set stage also capped at ``warm_share`` of clarabel's last cold
  iteration count and skipped for 1, 3, 7 … 31 ticks after a capped failure);
* *auto (pipelines)*: exactly ``pipeline_defaults()`` (``mode="auto"``: anytime up to 200 robots,
  distributed above);
* *anytime, floor at the cap*: the same with ``work_budget`` equal to the active-set cap, so the
  floor answers as soon as the warm paths give up (the alternative to clarabel cold);
* *clarabel*: a fresh ``solver="clarabel"`` filter (cold interior point on the same rows);
* *distributed*: ``mode="distributed"`` with and without the second pass.

Invasiveness: Σ‖u − û‖² of each answer over the centralised optimum's on the same tick (ticks
where the optimum intervenes). Timing is self-contained (no shared harness): ``timed`` below.
"""
from __future__ import annotations

import argparse  # noqa: E402
import collections  # noqa: E402
import dataclasses  # noqa: E402
import time  # noqa: E402

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np  # noqa: E402

from swarmdeck.safety import SafetyFilter  # noqa: E402
from swarmdeck.safety.config import pipeline_defaults  # noqa: E402
from swarmdeck.safety.scenes import crossing_scene, toward  # noqa: E402

DEFAULTS = pipeline_defaults()
WARM_CAP = int(DEFAULTS["active_set_max_solves"])
BUDGET = int(DEFAULTS["work_budget"])


def timed(fn, *args):
    """(process CPU s, result)."""
    t = time.process_time()
    out = fn(*args)
    return time.process_time() - t, out


def run(n: int, ticks: int, uncapped: bool = True, only: list[str] | None = None) -> dict:
    cfg, x, goals = crossing_scene(n, np.random.default_rng(0))
    filters = {
        "centralised": SafetyFilter(dataclasses.replace(cfg, mode="centralised")),
        "warm-capped": SafetyFilter(dataclasses.replace(cfg, mode="centralised", active_set_max_solves=WARM_CAP)),
        "anytime, fixed caps": SafetyFilter(dataclasses.replace(cfg, mode="anytime", active_set_max_solves=WARM_CAP,
                                                                work_budget=BUDGET)),
        "anytime": SafetyFilter(dataclasses.replace(cfg, **{**DEFAULTS, "mode": "anytime"})),
        "auto (pipelines)": SafetyFilter(dataclasses.replace(cfg, **DEFAULTS)),
        "anytime, floor at the cap": SafetyFilter(dataclasses.replace(cfg, mode="anytime", active_set_max_solves=WARM_CAP,
                                                                      work_budget=WARM_CAP)),
        "distributed": SafetyFilter(dataclasses.replace(cfg, mode="distributed")),
        "distributed 1 pass": SafetyFilter(dataclasses.replace(cfg, mode="distributed",
                                                               distributed_second_pass=False)),
    }
    if not uncapped:  # --no-uncapped: the optimum for the cost ratios from the warm-capped filter
        del filters["centralised"]
    if only:  # --only: these filters (the cost ratios over the first exact one kept)
        filters = {k: v for k, v in filters.items() if k in only or k == "anytime"}
    reference = next(k for k in ("centralised", "warm-capped", "anytime, fixed caps", "anytime") if k in filters)
    clar_cfg = dataclasses.replace(cfg, solver="clarabel")
    times = collections.defaultdict(list)
    cost = collections.defaultdict(list)
    answers = collections.defaultdict(collections.Counter)
    for _ in range(ticks):
        nom = toward(goals, x, cfg.max_speed)
        out = {}
        for name, flt in filters.items():
            t, (u, d) = timed(flt.filter, x, nom)
            assert d.ok, (name, d.status)
            times[name].append(t)
            out[name] = (u, d)
        t, (u, d) = timed(SafetyFilter(clar_cfg).filter, x, nom)
        assert d.ok, d.status
        times["clarabel"].append(t)
        for name in ("anytime", "anytime, floor at the cap"):
            if name in out:
                answers[name][out[name][1].answer] += 1
        c_opt = float(np.sum((out[reference][0] - nom) ** 2))
        if c_opt > 1e-12:
            for name, (u, _) in out.items():
                cost[name].append(float(np.sum((u - nom) ** 2)) / c_opt)
        x = x + out["anytime"][0] * cfg.dt
    return dict(n=n, times=times, cost=cost, answers=answers)


def cold(n: int, scenes: int) -> dict:
    """Single cold calls (a fresh filter per scene, no warm start) on the random dense scenes of
    ``bench_safety.py`` (jittered grid at 0.8 occupancy, pitch 0.188 m, random nominals): the
    default filter, the same without the cold dual prediction (``cold_dual=False``: clarabel and
    its polish, as before), and clarabel alone; process CPU time, the same scenes in one run."""
    from swarmdeck.safety import BarrierConfig
    from swarmdeck.safety.scenes import arena_for, grid_scene

    cfg = BarrierConfig() if n <= 100 else BarrierConfig(bounds=arena_for(n, 0.188, fill=0.8))
    rng = np.random.default_rng(1)
    variants = {"cold (default)": cfg, "cold, no dual prediction (before)": dataclasses.replace(cfg, cold_dual=False),
                "clarabel": dataclasses.replace(cfg, solver="clarabel")}
    SafetyFilter(cfg).filter(*grid_scene(n, rng, cfg, pitch=0.188))  # numba's load, not timed
    times = collections.defaultdict(list)
    methods: collections.Counter = collections.Counter()
    worst_diff = 0.0
    for _ in range(scenes):
        x, nom = grid_scene(n, rng, cfg, pitch=0.188)
        out = {}
        for name, c in variants.items():
            t, (u, d) = timed(SafetyFilter(c).filter, x, nom)
            assert d.ok, (name, d.status)
            times[name].append(t)
            out[name] = u
            if name == "cold (default)":
                methods[d.method] += 1
        worst_diff = max(worst_diff, float(np.max(np.abs(out["cold (default)"] - out["cold, no dual prediction (before)"]))))
    return dict(times=times, methods=methods, diff=worst_diff)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[100, 1000])
    ap.add_argument("--ticks", type=int, default=120)
    ap.add_argument("--no-uncapped", action="store_true",
                    help="leave out the uncapped centralised filter (seconds per tick at N = 1000)")
    ap.add_argument("--only", nargs="+", default=None,
                    help="only these filters (anytime and clarabel are always run), e.g. --only distributed")
    ap.add_argument("--cold", type=int, nargs="*", default=None,
                    help="instead: single cold calls at these N (default 20 100 1000), e.g. --cold 20 100")
    ap.add_argument("--scenes", type=int, default=30, help="scenes per N for --cold")
    args = ap.parse_args()
    if args.cold is not None:
        print(harness.machine())
        print("| N | scenes | filter | median ms | worst ms | median / clarabel's |")
        print("| --- | ---: | --- | ---: | ---: | ---: |")
        for n in args.cold or [20, 100, 1000]:
            r = cold(n, args.scenes)
            ref = np.median(r["times"]["clarabel"])
            for name, v in r["times"].items():
                print(f"| {n} | {args.scenes} | {name} | {1e3 * np.median(v):.2f} | {1e3 * max(v):.2f} | "
                      f"{np.median(v) / ref:.2f} |", flush=True)
            print(f"N = {n}: methods {dict(r['methods'])}; max |default − before| {r['diff']:.1e} m/s", flush=True)
        return
    print(f"{harness.machine()}; warm cap {WARM_CAP}, budget {BUDGET}, warm share {DEFAULTS['warm_share']}")
    print("| N | filter | median ms | worst ms | worst / clarabel's worst | mean cost / optimum | worst cost / optimum |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for n in args.n:
        r = run(n, args.ticks, not args.no_uncapped, args.only)
        worst_c = max(r["times"]["clarabel"])
        for name, v in r["times"].items():
            c = r["cost"].get(name, [])
            print(f"| {n} | {name} | {1e3 * np.median(v):.1f} | {1e3 * max(v):.1f} | {max(v) / worst_c:.2f} | "
                  + (f"{np.mean(c):.3f} | {max(c):.3f} |" if c else "– | – |"), flush=True)
        print(f"answers at N = {n}: " + "; ".join(f"{k}: {dict(v)}" for k, v in r["answers"].items()), flush=True)


if __name__ == "__main__":
    main()
