"""Benchmark: setting up N robots from the chargers to random start poses (issue 17).

Run: ``.venv/bin/python bench/bench_fleet.py`` (prints a markdown table; ``--runs K`` per N).

For N = 12, 20, 50: a fleet of N robots docked on random charger slots of the default layout
(50 slots on the 3.2 m × 2 m arena), start poses from ``random_initial_poses`` (the rps-style
generator, 0.23 m apart); each run a different seed. Per N: the median simulated time of the
setup (s), its median wall time (s, CPU of this process: ``time.process_time``), the fraction
of runs that needed the deadlock escape, failures (a setup over its time limit), collisions
and the largest final pose error; and the return to the chargers for the same runs.
Then the full-arena return: all 50 robots from random post-experiment poses onto all 50 slots
(``--return-runs`` seeds), finished k/K, simulated and CPU s (planning included), collisions; the
baseline in the same process is the staged maneuver (``return_maneuver(..., retrace=False)``,
drive each robot to its approach pose and back in) on the same seeds.
Baseline of the setup in the same process: the same number of control ticks through the same pipeline
(:func:`certify` with the fleet's barrier, zero nominal commands, the robots standing) — the
ratio says what the maneuver (controller, progress watch, escape) and the moving robots' barrier
rows add to the bare tick.
"""
from __future__ import annotations

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np  # noqa: E402

from swarmdeck.devices.fleet import FleetManager, SetupFailed, choose_slots, drive, return_maneuver  # noqa: E402
from swarmdeck.devices.initial_conditions import random_initial_poses  # noqa: E402
from swarmdeck.devices.pipeline import certify  # noqa: E402
from swarmdeck.devices.simulator import ArenaConfig  # noqa: E402


def baseline_cpu(fleet: FleetManager, steps: int) -> float:
    """CPU s of ``steps`` pipeline ticks of the fleet standing still (the same barrier)."""
    poses = fleet.poses()
    zero = np.zeros((fleet.n_robots, 2))
    t0 = time.process_time()
    for _ in range(steps):
        certify(poses, zero, fleet.params, fleet.filter)
    return time.process_time() - t0


def one(n: int, seed: int) -> dict:
    fleet = FleetManager(n, config=ArenaConfig(seed=seed))
    goals = random_initial_poses(n, fleet.config.bounds, rng=seed + 1000)
    out = {"ok": False, "escape": False, "collisions": 0}
    c0 = time.process_time()
    try:
        rep = fleet.setup(goals)
        out.update(ok=True, sim=rep.sim_time, cpu=time.process_time() - c0, escape=rep.escapes > 0,
                   err_cm=rep.max_position_error * 100, err_deg=float(np.rad2deg(rep.max_heading_error)),
                   steps=rep.steps)
        out["base"] = baseline_cpu(fleet, rep.steps)
    except SetupFailed as exc:
        out.update(sim=exc.report.sim_time, cpu=time.process_time() - c0, escape=exc.report.escapes > 0)
    c1 = time.process_time()
    try:
        ret = fleet.return_to_chargers()
        out.update(ret_ok=True, ret_sim=ret.sim_time, ret_cpu=time.process_time() - c1)
    except SetupFailed as exc:
        out.update(ret_ok=False, ret_sim=exc.report.sim_time, ret_cpu=time.process_time() - c1)
    out["collisions"] = fleet.sim.report.steps_with_collision
    return out


def full_return(seed: int, retrace: bool) -> dict:
    """50 robots set up to random poses, then returned onto all 50 slots (retraced plan or staged maneuver)."""
    fleet = FleetManager(50, config=ArenaConfig(seed=seed))
    fleet.setup(random_initial_poses(50, fleet.config.bounds, rng=seed + 1000))
    poses, layout, rows = fleet.poses(), fleet.fleet.layout, np.arange(50)
    c0 = time.process_time()
    slots = choose_slots(poses[:, :2], np.arange(layout.n_slots), layout)
    man = return_maneuver(poses, slots, layout, fleet.params, fleet.fleet.maneuver, retrace=retrace, occupied=[])
    try:
        rep = drive(fleet.sim, man, rows, fleet.filter, time_limit=fleet.fleet.time_limit(50), what="return")
        out = {"ok": True, "sim": rep.sim_time}
    except SetupFailed as exc:
        out = {"ok": False, "sim": exc.report.sim_time, "left": len(exc.report.not_at_pose)}
    out.update(cpu=time.process_time() - c0, collisions=fleet.sim.report.steps_with_collision)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=8)
    ap.add_argument("--return-runs", type=int, default=10)
    args = ap.parse_args()
    print(f"date {time.strftime('%Y-%m-%d')}, {harness.machine()}, {args.runs} runs per N")
    print("| N | setups finished | setup simulated s (median, max) | setup CPU s (median) | baseline ticks CPU s "
          "| ratio | runs needing the deadlock escape | largest pose error | collision steps | returns finished "
          "| return simulated s (median) | return CPU s (median) |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for n in (12, 20, 50):
        runs = [one(n, seed) for seed in range(args.runs)]
        ok = [r for r in runs if r["ok"]]
        sim = [r["sim"] for r in ok]
        cpu = [r["cpu"] for r in ok]
        base = [r["base"] for r in ok]
        rets = [r for r in runs if r.get("ret_ok")]
        med = statistics.median
        print(f"| {n} | {len(ok)}/{len(runs)} | {med(sim):.1f} ({max(sim):.1f}) | {med(cpu):.2f} | {med(base):.2f} | "
              f"{med(cpu) / med(base):.1f}x | {sum(r['escape'] for r in runs)}/{len(runs)} | "
              f"{max(r['err_cm'] for r in ok):.1f} cm / {max(r['err_deg'] for r in ok):.1f}° | "
              f"{sum(r['collisions'] for r in runs)} | {len(rets)}/{len(runs)} | "
              f"{med([r['ret_sim'] for r in rets]) if rets else float('nan'):.1f} | "
              f"{med([r['ret_cpu'] for r in rets]) if rets else float('nan'):.2f} |", flush=True)

    print("\n| full-arena return, 50 on 50 | finished | simulated s (median, max) | CPU s (median) | collision steps "
          "| robots left off their slots (failed runs) |")
    print("| --- | ---: | ---: | ---: | ---: | ---: |")
    for name, retrace in (("retraced plan", True), ("staged maneuver (baseline)", False)):
        runs = [full_return(seed, retrace) for seed in range(args.return_runs)]
        ok = [r for r in runs if r["ok"]]
        med = statistics.median
        sims = [r["sim"] for r in ok]
        left = [r["left"] for r in runs if not r["ok"]]
        print(f"| {name} | {len(ok)}/{len(runs)} | "
              + (f"{med(sims):.1f} ({max(sims):.1f})" if ok else "—") + " | "
              + f"{med([r['cpu'] for r in runs]):.2f} | {sum(r['collisions'] for r in runs)} | "
              + (f"{min(left)}–{max(left)}" if left else "—") + " |", flush=True)


if __name__ == "__main__":
    main()
