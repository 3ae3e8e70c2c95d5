"""Benchmark: verification throughput and the sandbox's overhead (issue 15).

Run: ``.venv/bin/python bench/bench_verify.py [--duration 60] [--runs 8] [--robots 20] [--repeats 3] [--no-ray]
[--overhead-only]``
(prints markdown tables).

* Throughput: ``verify`` of one 20-robot, 60 s (simulated) experiment with 8 runs (each raw and
  wrapped: 16 sandboxed runs) on a local pool of 1 and of 2 workers and on Ray (a local cluster
  started with ``num_cpus=2``, its start-up not counted); verifications per minute (wall) and the
  ratio to 1 worker. Target: 2 workers ≥ 1.8× one.
* Sandbox overhead: the same script and the same trusted Arena (barrier on), once in-process
  (``run_experiment``) and once in the jail (``run_sandboxed``): CPU seconds of this process
  (``getrusage``; for the sandboxed run plus the child's own CPU time, which it reports at its end:
  the jail's init does not pass it up through wait), median over ``--repeats``;
  overhead = sandboxed / in-process − 1.
  Target: ≤ 10 % of a 60 s run's CPU.
"""
from __future__ import annotations

import argparse
import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import platform  # noqa: E402
import resource  # noqa: E402
import statistics  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from swarmdeck.console.jobs.executors import LocalPoolExecutor, RayExecutor  # noqa: E402
from swarmdeck.console.jobs.plant import ArenaPlant  # noqa: E402
from swarmdeck.console.jobs.sandbox import run_sandboxed  # noqa: E402
from swarmdeck.console.jobs.verification import VerificationConfig, verify  # noqa: E402
from swarmdeck.devices.arena import Arena  # noqa: E402
from swarmdeck.devices.runner import run_experiment  # noqa: E402
from swarmdeck.devices.simulator import ArenaConfig  # noqa: E402

SCRIPT = '''
import numpy as np

def experiment(arena):
    """Robots on a circle of 0.8 m, each heading for the point opposite its start (through the middle)."""
    n = arena.n
    angles = np.arange(n) * 2 * np.pi / n
    goals = 0.8 * np.column_stack((np.cos(angles + np.pi), np.sin(angles + np.pi)))
    while True:
        arena.set_goals(goals)
        arena.step()
'''


def cpu_now() -> float:
    me = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def throughput(script: Path, config: VerificationConfig, executor) -> float:  # type: ignore[no-untyped-def]
    start = time.perf_counter()
    verify([script], config, executor)
    return 60.0 / (time.perf_counter() - start)


def overhead(script: Path, robots: int, duration: float, repeats: int) -> tuple[float, float]:
    inproc, sandboxed = [], []
    for k in range(repeats):
        c = cpu_now()
        direct = run_experiment(script, n_robots=robots, duration=duration, seed=k)
        assert direct.ok, direct.error
        inproc.append(cpu_now() - c)
        config = ArenaConfig(seed=k)
        c = cpu_now()
        out = run_sandboxed(script, lambda n, ic: ArenaPlant(Arena(n, initial_conditions=ic, config=config, duration=duration)),
                            n_robots=robots, duration=duration)
        assert out.ok and out.child_cpu_s is not None, out.error
        sandboxed.append(cpu_now() - c + out.child_cpu_s)
    return statistics.median(inproc), statistics.median(sandboxed)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--duration", type=float, default=60.0)
    parser.add_argument("--runs", type=int, default=8)
    parser.add_argument("--robots", type=int, default=20)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-ray", action="store_true")
    parser.add_argument("--overhead-only", action="store_true", help="skip the throughput table")
    args = parser.parse_args()
    folder = Path(tempfile.mkdtemp())
    script = folder / "circle_swap.py"
    script.write_text(SCRIPT)
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"load average {os.getloadavg()[0]:.1f}")
    inproc, sandboxed = overhead(script, args.robots, args.duration, args.repeats)
    print(f"\n| run ({args.robots} robots, {args.duration:g} s, barrier on) | CPU s (median of {args.repeats}) |\n| --- | ---: |")
    print(f"| in-process | {inproc:.2f} |\n| sandboxed (jail + child + pipe) | {sandboxed:.2f} |")
    print(f"| overhead | {100 * (sandboxed / inproc - 1):+.1f} % |")
    if args.overhead_only:
        return
    config = VerificationConfig(n_robots=args.robots, duration=args.duration, runs=args.runs, seed=0)
    rows = [("local pool, 1 worker", LocalPoolExecutor(1)), ("local pool, 2 workers", LocalPoolExecutor(2))]
    if not args.no_ray:
        import ray

        ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
        rows.append(("Ray (local cluster, num_cpus=2)", RayExecutor("auto")))
    print(f"\n| executor | verifications / min ({args.runs} runs × raw+wrapped) | ratio to 1 worker |\n| --- | ---: | ---: |")
    base = None
    for name, executor in rows:
        rate = throughput(script, config, executor)
        base = base or rate
        print(f"| {name} | {rate:.3f} | {rate / base:.2f}x |", flush=True)


if __name__ == "__main__":
    main()
