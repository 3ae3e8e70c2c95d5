"""Benchmark: what the jail hardening of issue 24 costs (seccomp filter, fresh session keyring, per-run uid with
its keyrings cleared afterwards, per-run cgroup with its OOM guard, scratch tmpfs).

Run: ``.venv/bin/python bench/bench_sandbox_hardening.py [--repeats 5] [--startups 20] [--robots 20]
[--duration 60] [--no-pin]`` (prints markdown tables).

Same process, same script, same trusted Arena (barrier on), alternately: the hardened sandbox
(what ``run_sandboxed`` always does) and the baseline — the same jail without any of the above
(``sandbox._BASELINE``, reachable only from this file through the private ``_run_sandboxed``; the
uid is then the old shared ``200000 + pid % 100000``), in each jail that works here.

* **start-up**: a script that builds its Arena and ends after one tick, ``--startups`` times per
  variant: wall time from the call to the trusted side's ``make_plant`` (the child booted,
  confined itself and imported the script), wall time of the whole call (set-up and tear-down
  included: cgroup, uid, keyrings) and CPU seconds of every process; median and worst.
* **per run / per tick**: the 20-robot, 60 s circle swap of ``bench_verify.py`` (1819 ticks),
  ``--repeats`` times per variant: CPU seconds of every process (this process — trusted loop,
  barrier, simulator, the OOM guard's thread, cgroup and uid bookkeeping —, its waited-for
  children — bwrap, the keyring-clearing fork —, the jail's processes as process A or the child
  reports them, and the fork server's CPU during the run); median and worst; the difference per
  tick. Target: hardened ≤ 5 % more CPU per run than the baseline.

This process (and so the fork server and the jails) runs on one core, as a pool worker does, unless
``--no-pin``; the run's cpuset is then that core.
"""
from __future__ import annotations

import argparse
import os
import resource  # noqa: E402
import statistics  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

from swarmdeck.console.sandbox import run as sandbox  # noqa: E402
from swarmdeck.console.sandbox.bundle import ScriptBundle  # noqa: E402
from swarmdeck.console.sandbox.confinement import JailConfig, SandboxLimits, choose_jail  # noqa: E402
from swarmdeck.console.sandbox.plant import ArenaPlant  # noqa: E402
from swarmdeck.console.sandbox.zygote import shared_fork_server  # noqa: E402
from swarmdeck.devices.arena import Arena  # noqa: E402
from swarmdeck.devices.simulator import ArenaConfig  # noqa: E402

CIRCLE = '''
import numpy as np

def experiment(arena):
    n = arena.n
    angles = np.arange(n) * 2 * np.pi / n
    goals = 0.8 * np.column_stack((np.cos(angles + np.pi), np.sin(angles + np.pi)))
    while True:
        arena.set_goals(goals)
        arena.step()
'''
ONE_TICK = '''
def experiment(arena):
    arena.step()
'''
VARIANTS = {"baseline": sandbox._BASELINE, "hardened": sandbox._FULL}


def cpu(who: int) -> float:
    usage = resource.getrusage(who)
    return usage.ru_utime + usage.ru_stime


def one_run(bundle: ScriptBundle, jail: str, variant: str, robots: int, duration: float, seed: int
            ) -> tuple[float, float, float, int]:
    """(wall s to make_plant, wall s of the call, CPU s of every process, ticks) of one sandboxed run."""
    config = ArenaConfig(seed=seed)
    server = shared_fork_server() if jail == "unshare" else None
    server_before = server.cpu_s() if server else 0.0
    me, kids = cpu(resource.RUSAGE_SELF), cpu(resource.RUSAGE_CHILDREN)
    booted: list[float] = []
    start = time.perf_counter()

    def make_plant(n, ic):  # type: ignore[no-untyped-def]
        booted.append(time.perf_counter() - start)
        return ArenaPlant(Arena(n, initial_conditions=ic, config=config, duration=duration))

    out = sandbox._run_sandboxed(bundle, make_plant, n_robots=robots, duration=duration, rps=None,
                                 limits=SandboxLimits(), trusted=False, cancelled=None,
                                 jail=JailConfig(order=(jail,)), hardening=VARIANTS[variant])
    wall = time.perf_counter() - start
    assert out.ok and out.child_cpu_s is not None and out.jail == jail, out.error
    assert (out.cgroup is not None) == (variant == "hardened")
    total = cpu(resource.RUSAGE_SELF) - me + cpu(resource.RUSAGE_CHILDREN) - kids + out.child_cpu_s
    total += (server.cpu_s() - server_before) if server else 0.0
    return booted[0], wall, total, out.ticks


def stats(values: list[float], scale: float = 1.0, digits: int = 3) -> str:
    """``"median / worst"`` of ``values`` × ``scale``."""
    t = harness.timing(values)
    return f"{t.median * scale:.{digits}f} / {t.worst * scale:.{digits}f}"


def load() -> str:
    return "/".join(f"{x:.1f}" for x in os.getloadavg())


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=5, help="long runs per variant and jail")
    parser.add_argument("--startups", type=int, default=20, help="one-tick runs per variant and jail")
    parser.add_argument("--robots", type=int, default=20)
    parser.add_argument("--duration", type=float, default=60.0)
    parser.add_argument("--no-pin", action="store_true")
    args = parser.parse_args()
    folder = Path(tempfile.mkdtemp())
    (folder / "circle_swap.py").write_text(CIRCLE)
    (folder / "one_tick.py").write_text(ONE_TICK)
    circle = ScriptBundle.from_path(folder / "circle_swap.py")
    tick = ScriptBundle.from_path(folder / "one_tick.py")
    everywhere = os.sched_getaffinity(0)
    if not args.no_pin:
        os.sched_setaffinity(0, {max(everywhere)})
    jails = [j for j in ("unshare", "bwrap") if choose_jail(JailConfig(order=(j,)))[0] == j]
    print(f"{harness.machine()}, {'unpinned' if args.no_pin else 'pinned to one core'}, load average {load()}")
    for jail in jails:
        one_run(tick, jail, "hardened", 2, 0.1, 0)  # warm up (the fork server, the filter, the jail layout)
    print(f"\n**start-up** (a one-tick script, 2 robots; median / worst of {args.startups})\n")
    print("| jail | variant | to make_plant, ms | whole call, ms | CPU all processes, ms |\n| --- | --- | ---: | ---: | ---: |")
    for jail in jails:
        rows: dict[str, list[tuple[float, float, float, int]]] = {v: [] for v in VARIANTS}
        for k in range(args.startups):
            for variant in VARIANTS:
                rows[variant].append(one_run(tick, jail, variant, 2, 0.1, k))
        for variant, runs in rows.items():
            print(f"| {jail} | {variant} | {stats([r[0] for r in runs], 1e3, 1)} | {stats([r[1] for r in runs], 1e3, 1)}"
                  f" | {stats([r[2] for r in runs], 1e3, 1)} |", flush=True)
    print(f"\n**per run** ({args.robots} robots, {args.duration:g} s, barrier on; CPU s of every process, median / "
          f"worst of {args.repeats})\n")
    print("| jail | baseline CPU s | hardened CPU s | hardened − baseline (medians) | per tick |\n"
          "| --- | ---: | ---: | ---: | ---: |")
    for jail in jails:
        rows = {v: [] for v in VARIANTS}
        for k in range(args.repeats):
            for variant in VARIANTS:
                rows[variant].append(one_run(circle, jail, variant, args.robots, args.duration, k))
        base = statistics.median(r[2] for r in rows["baseline"])
        hard = statistics.median(r[2] for r in rows["hardened"])
        ticks = rows["hardened"][0][3]
        print(f"| {jail} | {stats([r[2] for r in rows['baseline']])} | {stats([r[2] for r in rows['hardened']])} | "
              f"{hard - base:+.3f} s ({100 * (hard / base - 1):+.1f} %) | {1e6 * (hard - base) / ticks:+.1f} µs |",
              flush=True)
    print(f"\nload average after: {load()}")
    os.sched_setaffinity(0, everywhere)


if __name__ == "__main__":
    main()
