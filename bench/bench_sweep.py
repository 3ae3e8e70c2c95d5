"""Benchmark: sweep throughput and the sandbox's per-run overhead (issue 31, item 2).

Run: ``.venv/bin/python bench/bench_sweep.py [--robots 20] [--duration 30] [--runs 4] [--no-ray]`` (prints markdown
rows for bench/RESULTS.md, "sweeps").

* Throughput: one sweep of ``--runs`` runs (2 gains × runs/2 seeds; ``--robots`` robots, ``--duration`` simulated s,
  barrier on, verification's disturbances) into a fresh folder on a local pool of 1 and of 2 workers and on Ray (a
  local cluster with ``num_cpus=2``, its start-up not counted); runs per minute (wall, the pool's start-up included)
  and the ratio to 1 worker. The load average before and after each row is printed: the ratio only means something
  on an otherwise idle machine.
* Per-run overhead of the sandbox: the same script and point in this process (``run_experiment``, the barrier on,
  the Arena simulated) and as a sweep run (``run_point``: the jail, the pipe, the trusted plant with disturbances,
  the row with H), alternately, ``--repeats`` times after one warm-up sandboxed run (the fork server up, as in a
  pool worker); median wall s and CPU s (the sandboxed run's CPU: trusted side + jail, as the row reports it).
"""
from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

from swarmdeck.console.sandbox.bundle import ScriptBundle  # noqa: E402
from swarmdeck.console.sandbox.executors import LocalPoolExecutor, RayExecutor  # noqa: E402
from swarmdeck.console.sandbox.verification import VerificationConfig  # noqa: E402
from swarmdeck.console.sweep.campaign import SweepSpec, plan, run_sweep  # noqa: E402
from swarmdeck.console.sweep.design import parse_axis  # noqa: E402
from swarmdeck.console.sweep.runs import run_point  # noqa: E402
from swarmdeck.devices.experiment_params import PARAMS_ENV  # noqa: E402
from swarmdeck.devices.runner import run_experiment  # noqa: E402

SCRIPT = b'''
import numpy as np
from swarmdeck.devices import params, record_metrics

p = params(gain=1.0)

def experiment(arena):
    """Robots heading for the point opposite their start through the middle, at speed gain x 0.1 m/s."""
    start = arena.positions().copy()
    goals = -start
    while True:
        x = arena.positions()
        d = goals - x
        dist = np.linalg.norm(d, axis=1, keepdims=True)
        arena.set_velocities(np.minimum(p.gain * 0.1, dist) * d / np.maximum(dist, 1e-9))
        record_metrics(mean_goal_distance=float(dist.mean()))
        arena.step()
'''


def spec(robots: int, duration: float, runs: int) -> SweepSpec:
    return SweepSpec(ScriptBundle.single("crossing.py", SCRIPT), (parse_axis("gain=0.5,1"),), seeds=max(1, runs // 2),
                     robots=(robots,), config=VerificationConfig(duration=duration))


def throughput(args: argparse.Namespace) -> None:
    print(f"\nsweep throughput: {args.runs} runs, {args.robots} robots, {args.duration:g} s simulated, barrier on")
    print(harness.table_header(["executor", "runs / min", "ratio to 1 worker", "load before → after"]))
    executors = [("local pool, 1 worker", lambda: LocalPoolExecutor(1)), ("local pool, 2 workers", lambda: LocalPoolExecutor(2))]
    if not args.no_ray:
        executors.append(("Ray local (num_cpus=2)", lambda: RayExecutor("local", num_cpus=2)))
    one = None
    for name, make in executors:
        executor = make()
        if isinstance(executor, RayExecutor):
            executor._connect()  # the cluster's start-up is not the sweep's
        before = os.getloadavg()[0]
        with tempfile.TemporaryDirectory() as out:
            t0 = time.perf_counter()
            result = run_sweep(spec(args.robots, args.duration, args.runs), out, executor)
            wall = time.perf_counter() - t0
        rate = 60.0 * len(result.rows) / wall
        one = one or rate
        print(harness.table_row(name, f"{rate:.2f}", f"{rate / one:.2f}", f"{before:.1f} → {os.getloadavg()[0]:.1f}"))
        if isinstance(executor, RayExecutor):
            executor.ray.shutdown()


def overhead(args: argparse.Namespace) -> None:
    the_plan = plan(spec(args.robots, args.duration, 2))
    run = the_plan.runs[0]
    script = os.path.join(tempfile.mkdtemp(prefix="bench-sweep-"), "crossing.py")
    with open(script, "wb") as f:
        f.write(SCRIPT)
    run_point(run)  # warm-up: the fork server starts once per worker
    inproc_wall, inproc_cpu, box_wall, box_cpu = [], [], [], []
    for _ in range(args.repeats):
        os.environ[PARAMS_ENV] = '{"gain": 0.5}'
        c0, t0 = time.process_time(), time.perf_counter()
        run_experiment(script, n_robots=args.robots, duration=args.duration, seed=0, safety=True)
        inproc_wall.append(time.perf_counter() - t0)
        inproc_cpu.append(time.process_time() - c0)
        del os.environ[PARAMS_ENV]
        t0 = time.perf_counter()
        row = run_point(run)
        box_wall.append(time.perf_counter() - t0)
        box_cpu.append(float(row["cpu_s"] or 0.0))
    w0, w1 = statistics.median(inproc_wall), statistics.median(box_wall)
    c0_, c1 = statistics.median(inproc_cpu), statistics.median(box_cpu)
    print(f"\nper-run overhead of the sandbox: {args.robots} robots, {args.duration:g} s simulated, "
          f"median of {args.repeats}")
    print(harness.table_header(["run", "wall s", "CPU s", "overhead (wall / CPU)"]))
    print(harness.table_row("in-process (run_experiment)", f"{w0:.2f}", f"{c0_:.2f}", "—"))
    print(harness.table_row("sweep run (sandbox, disturbances, row)", f"{w1:.2f}", f"{c1:.2f}",
                            f"{w1 / w0 - 1:+.0%} / {c1 / c0_ - 1:+.0%}"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=20)
    parser.add_argument("--duration", type=float, default=30.0)
    parser.add_argument("--runs", type=int, default=4)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-ray", action="store_true")
    parser.add_argument("--overhead-only", action="store_true")
    args = parser.parse_args()
    print(harness.machine())
    overhead(args)
    if not args.overhead_only:
        throughput(args)


if __name__ == "__main__":
    main()
