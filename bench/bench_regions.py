"""Jobs per hour on one 50-robot simulated floor: one job at a time vs one job per region (issue 30.1).

A queue of 6-robot, 30 s jobs (the rendezvous example, unmodified) runs on a simulated floor of 50 robots twice,
in the same process: (a) one region covering the whole floor, so one job at a time; (b) the floor as 2 × 2
regions (12–13 robots parked in each), one job per region at once. Every job is set up at its start poses,
runs 30 s and returns its robots, through the floor's one barrier. Jobs per hour are counted in floor time (the
simulated clock: a real floor runs in real time; only jobs that ended well count), so the ratio is what a lab
would see; the wall time the
simulation took is reported beside it. The runs also check the safety claims: robots outside their region and
contacts (both 0 expected).

ETA error: the portal's plan (:func:`swarmdeck.console.portal.scheduler.plan`: one lane per region, each job's
occupancy its declared duration plus the floor's measured set-up/return overhead — the median over the jobs ended so
far, :func:`~swarmdeck.console.portal.scheduler.overhead`) replayed at every event of the queue (a job taken or
ended), as the portal recomputes it whenever the queue moves: each job's error is its actual start minus the start
the plan gave it at the last event before it started (floor time, s); the plan at time 0 (no history: the default
overhead) is reported beside it.

    .venv/bin/python bench/bench_regions.py            # 8 jobs (≈ 3 min on a loaded 2-core machine)
    .venv/bin/python bench/bench_regions.py --jobs 4   # quicker
    .venv/bin/python bench/bench_regions.py --start parked   # jobs start where their robots stand
"""
from __future__ import annotations

import argparse
import time

import harness  # before numpy loads: pins BLAS

from swarmdeck.console.portal.scheduler import DEFAULT_OVERHEAD_S, Lane, Pending, occupancy, overhead, plan
from swarmdeck.console.runtime.region_jobs import QueuedJob, run_queue
from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.devices.fleet.floor import simulated_floor
from swarmdeck.devices.fleet.regions import RegionLayout
from swarmdeck.examples.rendezvous import experiment

ROBOTS, DURATION, FLOOR_ROBOTS = 6, 30.0, 50


def run(layout: RegionLayout, per_region: dict[str, int], jobs: int, start: str | None,
        duration: float = DURATION) -> dict:
    floor = simulated_floor(layout, per_region)
    queue = [QueuedJob(f"job{k}", experiment, ROBOTS, duration, seed=k, start_poses=start) for k in range(jobs)]
    t0 = time.perf_counter()
    done = run_queue(floor, queue)
    wall = time.perf_counter() - t0
    floor_s = float(floor.ports.read().time)
    ok = sum(1 for _, r in done if r.error is None and r.run is not None and r.run.error is None)
    setups = [r.setup.get("seconds", 0.0) for _, r in done]
    returns = [r.returned.get("seconds", 0.0) for _, r in done]
    report = floor.ports.report
    eta_now, eta_first = eta_errors(layout, queue, done)
    return {"eta_median": _pct(eta_now, 50), "eta_p90": _pct(eta_now, 90), "eta0_median": _pct(eta_first, 50),
            "eta0_p90": _pct(eta_first, 90),"jobs": len(done), "ok": ok, "floor_s": floor_s, "wall_s": wall, "per_hour": 3600.0 * ok / floor_s,
            "setup_s": sum(setups) / len(setups), "return_s": sum(returns) / len(returns),
            "outside": floor.stats.outside, "contacts": report.collision_pairs, "robots": len(floor.reading().ids)}


def eta_errors(layout: RegionLayout, queue: list[QueuedJob], done: list) -> tuple[list[float], list[float]]:
    """(|actual − planned start| of each job at the last queue event before it started, the same for the plan at
    time 0), floor s — the plan replayed from the jobs' recorded floor times (module docstring)."""
    runs = {job.name: (r.started_s, r.ended_s) for job, r in done}
    order = {job.name: k for k, job in enumerate(queue)}
    events = sorted({0.0, *(t for pair in runs.values() for t in pair if t is not None)})
    cap = layout.capacity()
    latest: dict[str, float] = {}
    first: dict[str, float] = {}
    for t in events:  # a few dozen events, once
        waiting = [j for j in queue if runs[j.name][0] is not None and runs[j.name][0] > t]
        if not waiting:
            continue
        ended = [(runs[j.name][0], runs[j.name][1], j.duration) for j in queue
                 if runs[j.name][1] is not None and runs[j.name][1] <= t]
        est = overhead(ended)
        lanes = []
        for k, name in enumerate(layout.names):
            busy = [(r.started_s, r.started_s + occupancy(j.duration, est)) for j, r in done
                    if r.region == name and r.started_s is not None and r.started_s <= t < (r.ended_s or 0.0)]
            lanes.append(Lane("floor", k, "simulated", cap[name], busy))
        pending = [Pending(order[j.name], 1, j.robots, j.duration) for j in waiting]
        placed = plan(pending, lanes, [], t, {"floor": est if ended else DEFAULT_OVERHEAD_S})
        for j in waiting:
            if order[j.name] in placed:
                latest[j.name] = placed[order[j.name]].start
                first.setdefault(j.name, placed[order[j.name]].start)
    now = [abs(runs[n][0] - p) for n, p in latest.items()]
    zero = [abs(runs[n][0] - p) for n, p in first.items()]
    return now, zero


def _pct(values: list[float], q: float) -> float:
    import numpy as np

    return float(np.percentile(values, q)) if values else float("nan")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=8)
    parser.add_argument("--duration", type=float, default=DURATION, help="each job's, s (a quick check: 3)")
    parser.add_argument("--start", choices=("random", "parked"), default="random",
                        help="the jobs' start poses: random valid ones in the region (set up by driving there) or "
                             "where the robots stand (no set-up drive)")
    args = parser.parse_args()
    print(harness.machine())
    whole = RegionLayout.grid(DEFAULT_BOUNDS, 1, 1)
    quad = RegionLayout.grid(DEFAULT_BOUNDS, 2, 2)
    split = {"r0c0": 13, "r0c1": 13, "r1c0": 12, "r1c1": 12}
    start = None if args.start == "random" else args.start
    rows = {"one at a time": run(whole, {"r0c0": FLOOR_ROBOTS}, args.jobs, start, args.duration),
            "2 × 2 regions": run(quad, split, args.jobs, start, args.duration)}
    print(f"{args.jobs} jobs of {ROBOTS} robots, {args.duration:g} s each, start poses {args.start}, on a "
          f"{FLOOR_ROBOTS}-robot floor "
          f"(baseline {harness.baseline().median * 1e3:.1f} ms)")
    print("| mode | jobs ok | floor time (s) | jobs ok per hour | set-up (s, mean) | return (s, mean) | outside | contacts "
          "| ETA error median / p90 (s) | at time 0 | wall time (s) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for name, r in rows.items():
        print(f"| {name} | {r['ok']}/{r['jobs']} | {r['floor_s']:.0f} | {r['per_hour']:.0f} | {r['setup_s']:.1f} | "
              f"{r['return_s']:.1f} | {r['outside']} | {r['contacts']} | {r['eta_median']:.1f} / {r['eta_p90']:.1f} | "
              f"{r['eta0_median']:.1f} / {r['eta0_p90']:.1f} | {r['wall_s']:.0f} |")
    ratio = rows["2 × 2 regions"]["per_hour"] / rows["one at a time"]["per_hour"]
    print(f"regions / one at a time: {ratio:.2f}x (target >= 3x)")


if __name__ == "__main__":
    main()
