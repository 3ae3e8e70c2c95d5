"""Benchmark: verification throughput and the sandbox's overhead (issue 15).

Run: ``.venv/bin/python bench/bench_verify.py [--duration 60] [--runs 8] [--robots 20] [--repeats 3] [--no-ray]
[--overhead-only | --throughput-only] [--queue K [--concurrent J]]`` from the repository root
(prints markdown tables).

* Sandbox overhead: the same script and the same trusted Arena (barrier on), once in-process
  (``run_experiment``) and once in the jail (``run_sandboxed``), alternately, ``--repeats`` times;
  CPU seconds of **every** process a run uses, median over the repeats; overhead =
  sandboxed / in-process − 1. Target: ≤ 10 % of a 60 s run's CPU. This process (and so the
  fork server and the jails it starts) runs on one core, as a verification pool worker does
  (``LocalPoolExecutor(pin=True)``); ``--no-pin`` lets the scheduler place them.

  - ``unshare`` jail: this process (``getrusage`` self: the trusted loop, barrier, simulator,
    pipe) + the jail's processes (the script's process, the jail's init and process A, measured
    by A outside the jail with ``getrusage`` of everything it waited for) + the fork server's
    CPU during the run (the forks; ``/proc/PID/stat``). The fork server's own start-up (Python,
    numpy, swarmdeck: once per worker process, shared by all its runs) is shown on its own row.
  - floor: the in-process run plus one pipe round trip per tick to a process that only echoes
    (both processes' CPU): what two processes taking turns every tick cost with no sandbox code.
  - ``bwrap`` jail: this process + the child's own CPU (it reports it at its end; the jail's
    init does not pass it up through wait) + this process's waited-for children (bwrap).

* Throughput: ``verify`` of one 20-robot, 60 s (simulated) experiment with 8 runs (each raw and
  wrapped: 16 sandboxed runs) on a local pool of 1 and of 2 workers and on Ray (a local cluster
  started with ``num_cpus=2``, its start-up not counted); verifications per minute (wall) and the
  ratio to 1 worker. Target: 2 workers ≥ 1.8× one. The load average before and after each row is
  printed: the ratio only means something on an otherwise idle machine. Measured twice: with the default
  ``paced_runs`` (one raw run ticks in real time, so no verification takes less than the declared duration of wall
  time) and with none (``--paced-runs K`` sets the first), where the ratio is the pool's scaling alone.
  With ``--queue K``: K verifications submitted together and drained by ``--concurrent J`` threads on one executor
  whose workers are kept (as the portal's verification threads run a queue of jobs); verifications per minute, the
  ratio to 1 worker, per worker, and the CPU per verification of the runs and of this (collecting) process.

* Fairness of the overhead table: every kind runs once untimed first (lazy imports, the barrier's first solves, the
  jail layout: a worker pays them once), the kinds alternate in an order rotating every repeat, and the median and
  the worst of the repeats are printed with every run (bench/RESULTS.md "verification queue").
"""
from __future__ import annotations

import argparse
import os
import queue
import resource  # noqa: E402
import statistics  # noqa: E402
import tempfile  # noqa: E402
import threading
import time  # noqa: E402
from contextlib import nullcontext  # noqa: E402
from dataclasses import replace  # noqa: E402
from functools import partial  # noqa: E402
from pathlib import Path  # noqa: E402

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

from swarmdeck.console.sandbox.confinement import JailConfig, choose_jail  # noqa: E402
from swarmdeck.console.sandbox.executors import LocalPoolExecutor, RayExecutor  # noqa: E402
from swarmdeck.console.sandbox.plant import ArenaPlant  # noqa: E402
from swarmdeck.console.sandbox.run import run_sandboxed  # noqa: E402
from swarmdeck.console.sandbox.verification import VerificationConfig, verify  # noqa: E402
from swarmdeck.console.sandbox.zygote import shared_fork_server  # noqa: E402
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


def cpu_self() -> float:
    me = resource.getrusage(resource.RUSAGE_SELF)
    return me.ru_utime + me.ru_stime


def cpu_children() -> float:
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return kids.ru_utime + kids.ru_stime


def throughput(script: Path, config: VerificationConfig, executor) -> float:  # type: ignore[no-untyped-def]
    start = time.perf_counter()
    verify([script], config, executor)
    return 60.0 / (time.perf_counter() - start)


def queued(script: Path, config: VerificationConfig, executor, k: int, concurrent: int) -> tuple[float, float, float]:  # type: ignore[no-untyped-def]
    """``k`` verifications submitted together, drained by ``concurrent`` threads on one executor whose workers are
    kept (as the portal's :class:`~swarmdeck.console.portal.workers.VerificationWorkers` run a queue of jobs):
    (verifications per minute of wall time, CPU s of the runs per verification, CPU s of this process per
    verification — the trusted side's collection, not the runs). The pool's start-up is counted (once per queue)."""
    jobs: queue.Queue[int] = queue.Queue()
    for j in range(k):
        jobs.put(j)
    cpu: list[float] = []
    failed: list[BaseException] = []

    def drain() -> None:
        while True:
            try:
                j = jobs.get_nowait()
            except queue.Empty:
                return
            try:
                cpu.append(verify([script], replace(config, seed=j), executor).cpu_s)
            except BaseException as exc:  # noqa: BLE001 - reported below
                failed.append(exc)
                return

    kept = getattr(executor, "kept", None)
    me = cpu_self()
    start = time.perf_counter()
    with kept() if kept is not None else nullcontext():
        threads = [threading.Thread(target=drain, daemon=True) for _ in range(concurrent)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(timeout=3600)
            assert not t.is_alive(), "a verification thread did not end within an hour"
    wall = time.perf_counter() - start
    assert not failed, failed
    return 60.0 * k / wall, sum(cpu) / k, (cpu_self() - me) / k


def sandboxed_cpu(script: Path, robots: int, duration: float, seed: int, jail: str) -> float:
    config = ArenaConfig(seed=seed)
    server = shared_fork_server() if jail == "unshare" else None
    server_before = server.cpu_s() if server else 0.0
    me, kids = cpu_self(), cpu_children()
    out = run_sandboxed(script, lambda n, ic: ArenaPlant(Arena(n, initial_conditions=ic, config=config, duration=duration)),
                        n_robots=robots, duration=duration, jail=JailConfig(order=(jail,)))
    assert out.ok and out.child_cpu_s is not None and out.jail == jail, out.error
    total = cpu_self() - me + out.child_cpu_s
    total += (server.cpu_s() - server_before) if server else cpu_children() - kids
    return total


def echo_floor(script: Path, robots: int, duration: float, seed: int) -> float:
    """CPU of the in-process run plus one pipe round trip per tick to a process that only echoes:
    the cost of two processes taking turns every tick, with no sandbox code at all."""
    to_r, to_w = os.pipe()
    back_r, back_w = os.pipe()
    kids, me = cpu_children(), cpu_self()
    pid = os.fork()
    if pid == 0:  # the echo: reads a poses-sized frame, answers with a commands-sized one
        os.close(to_w)
        while os.read(to_r, 4096):
            os.write(back_w, bytes(333))
        os._exit(0)
    frame = bytes(497)

    def hop(arena: Arena) -> None:
        os.write(to_w, frame)
        os.read(back_r, 4096)

    direct = run_experiment(script, n_robots=robots, duration=duration, seed=seed, on_step=hop)
    assert direct.ok, direct.error
    os.close(to_w)
    os.waitpid(pid, 0)
    for fd in (to_r, back_r, back_w):
        os.close(fd)
    return cpu_self() - me + cpu_children() - kids


def in_process(script: Path, robots: int, duration: float, seed: int) -> float:
    """CPU of the in-process run (this process: the script, its Arena, the barrier, the simulator)."""
    me = cpu_self()
    direct = run_experiment(script, n_robots=robots, duration=duration, seed=seed)
    assert direct.ok, direct.error
    return cpu_self() - me


def overhead(script: Path, robots: int, duration: float, repeats: int, jails: list[str]) -> dict[str, list[float]]:
    """Each kind's CPU per run, ``repeats`` times. Fair to each: one short untimed run of every kind first (lazy
    imports, the barrier's first solve, the jail layout — a worker pays them once, not per run), then the kinds
    alternate in an order that rotates every repeat, so none always runs first (after another kind's memory)."""
    kinds = {"in-process": partial(in_process, script, robots), "echo": partial(echo_floor, script, robots),
             **{j: partial(sandboxed_cpu, script, robots, jail=j) for j in jails}}
    for run in kinds.values():  # the warm-up (short, untimed)
        run(1.0, 99)
    runs: dict[str, list[float]] = {name: [] for name in kinds}
    names = list(kinds)
    for k in range(repeats):
        for name in names[k % len(names):] + names[:k % len(names)]:
            runs[name].append(kinds[name](duration, k))
    return runs


def load() -> str:
    return "/".join(f"{x:.1f}" for x in os.getloadavg())


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--duration", type=float, default=60.0)
    parser.add_argument("--runs", type=int, default=8)
    parser.add_argument("--robots", type=int, default=20)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-ray", action="store_true")
    parser.add_argument("--overhead-only", action="store_true", help="skip the throughput table")
    parser.add_argument("--throughput-only", action="store_true", help="skip the overhead table")
    parser.add_argument("--no-pin", action="store_true", help="overhead: do not pin this process to one core")
    parser.add_argument("--paced-runs", type=int, default=VerificationConfig.paced_runs,
                        help="throughput: the configuration's paced (real-time) runs; a second table row set has none")
    parser.add_argument("--queue", type=int, default=0, metavar="K",
                        help="throughput: K verifications submitted together, drained by --concurrent threads on one "
                             "executor with kept workers (as the portal verifies a queue of jobs); 0: one verification")
    parser.add_argument("--concurrent", type=int, default=2, metavar="J",
                        help="with --queue: verifications run at once (the portal's --verify-concurrent; default 2)")
    args = parser.parse_args()
    folder = Path(tempfile.mkdtemp())
    script = folder / "circle_swap.py"
    script.write_text(SCRIPT)
    print(f"{harness.machine()}, load average (1/5/15 min) {load()}")
    if not args.throughput_only:
        everywhere = os.sched_getaffinity(0)
        if not args.no_pin:
            os.sched_setaffinity(0, {max(everywhere)})
        jails = [j for j in ("unshare", "bwrap") if choose_jail(JailConfig(order=(j,)))[0] == j]
        startup = shared_fork_server().startup_cpu_s if "unshare" in jails else None
        runs = overhead(script, args.robots, args.duration, args.repeats, jails)
        medians = {name: statistics.median(values) for name, values in runs.items()}
        base, worst = medians["in-process"], max(runs["in-process"])
        print(f"\n| run ({args.robots} robots, {args.duration:g} s, barrier on) | CPU s, all processes: median of "
              f"{args.repeats} | overhead | worst of {args.repeats} | overhead (worst/worst) |\n"
              "| --- | ---: | ---: | ---: | ---: |")
        print(f"| in-process | {base:.3f} | — | {worst:.3f} | — |")
        shown = [("echo", "in-process + a per-tick pipe round trip to an echo process (the floor of any "
                          "two-process split)")] + [(j, f"sandboxed, {j} jail") for j in jails]
        for name, label in shown:
            m, w = medians[name], max(runs[name])
            print(f"| {label} | {m:.3f} | {100 * (m / base - 1):+.1f} % | {w:.3f} | {100 * (w / worst - 1):+.1f} % |")
        if startup is not None:
            print(f"| (fork server start-up, once per worker process) | {startup:.3f} | "
                  f"{100 * startup / base:+.1f} % of one run | | |")
        print("\nevery run (CPU s, in run order within each kind): " + "; ".join(
            f"{name} " + ", ".join(f"{v:.3f}" for v in values) for name, values in runs.items()))
        print(f"\n{'unpinned' if args.no_pin else 'pinned to one core'}; load average after: {load()}")
        os.sched_setaffinity(0, everywhere)
    if args.overhead_only:
        return
    rows = [("local pool, 1 worker", 1, LocalPoolExecutor(1)), ("local pool, 2 workers", 2, LocalPoolExecutor(2))]
    if not args.no_ray:
        import ray

        ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
        rows.append(("Ray (local cluster, num_cpus=2)", 2, RayExecutor("auto")))
    if args.queue:
        print(f"\n| executor | paced runs | verifications / min ({args.queue} queued, {args.concurrent} at once; "
              f"{args.runs} runs × raw+wrapped) | ratio to 1 worker | per worker | CPU s of the runs / verification "
              "| CPU s of this process / verification | load before | load after |\n"
              "| --- | ---: | ---: | ---: | ---: | ---: | ---: | --- | --- |")
    else:
        print(f"\n| executor | paced runs | verifications / min ({args.runs} runs × raw+wrapped) | ratio to 1 worker | "
              "load before | load after |\n| --- | ---: | ---: | ---: | --- | --- |")
    for paced in sorted({args.paced_runs, 0}, reverse=True):  # the default (a real-time run), then compute alone
        config = VerificationConfig(n_robots=args.robots, duration=args.duration, runs=args.runs, seed=0,
                                    paced_runs=paced)
        base_rate = None
        for name, workers, executor in rows:
            before = load()
            if args.queue:
                rate, runs_cpu, own_cpu = queued(script, config, executor, args.queue, args.concurrent)
                base_rate = base_rate or rate
                print(f"| {name} | {paced} | {rate:.3f} | {rate / base_rate:.2f}x | {rate / workers:.3f} | "
                      f"{runs_cpu:.2f} | {own_cpu:.2f} | {before} | {load()} |", flush=True)
            else:
                rate = throughput(script, config, executor)
                base_rate = base_rate or rate
                print(f"| {name} | {paced} | {rate:.3f} | {rate / base_rate:.2f}x | {before} | {load()} |", flush=True)


if __name__ == "__main__":
    main()
