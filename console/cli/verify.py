"""``swarmdeck verify SCRIPT...``: verify untrusted experiment scripts in sandboxed simulation.

Exit status: 0 accepted (with or without barrier bypass), 1 rejected, 2 usage or
infrastructure error (bad option, unreadable script, no confinement without
``--trusted``, Ray unavailable).
"""
from __future__ import annotations

import argparse
import json
import sys

NAME = "verify"
HELP = "verify experiment scripts in sandboxed simulation: safety score, verdict, JSON/HTML report"
ORDER = 25


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = ("verdicts: rejected | accepted (runs with the barrier) | accepted, may bypass the barrier. "
                     "exit status: 0 accepted, 1 rejected, 2 usage or infrastructure error.")
    parser.add_argument("scripts", nargs="+", metavar="SCRIPT",
                        help="experiment scripts (experiment(arena) or rps style): .py files, or directories run from "
                             "their --entry file with sibling modules importable")
    parser.add_argument("--entry", default=None, metavar="FILE",
                        help="for a directory SCRIPT: the file to run, relative to it (default main.py)")
    parser.add_argument("--robots", type=int, default=None, metavar="N", help="declared number of robots (default: the script's)")
    parser.add_argument("--duration", type=float, default=30.0, metavar="S", help="declared duration in simulated seconds (default 30)")
    parser.add_argument("--runs", type=int, default=8, metavar="K", help="runs per script, each without and with the barrier (default 8)")
    parser.add_argument("--seed", type=int, default=0, help="base seed of the initial conditions and disturbances (default 0)")
    parser.add_argument("--workers", type=int, default=None, metavar="W", help="local worker processes (default: number of cores)")
    parser.add_argument("--ray", default=None, metavar="auto|ADDRESS|local",
                        help="run on a Ray cluster ('auto': the running one; 'local': start one here); needs swarmdeck[ray]")
    parser.add_argument("--bypass-threshold", type=float, default=0.99, metavar="S",
                        help="safety score every raw run must reach, with no contact, to bypass the barrier (default 0.99)")
    parser.add_argument("--tick-budget", type=float, default=1.0, metavar="S",
                        help="per-tick compute budget of the script, wall seconds (default 1.0)")
    parser.add_argument("--trusted", action="store_true",
                        help="run the scripts unconfined where this machine cannot confine them (no jail works)")
    parser.add_argument("--allow-no-cgroup", action="store_true",
                        help="verify even where no cgroup can be created per run (not root, no memory/pids controller): "
                             "then only per-process limits bound a run's memory, processes and CPU")
    parser.add_argument("--jail", choices=("unshare", "bwrap"), default=None,
                        help="confine with this jail only (default: unshare — Linux namespaces around a pre-loaded "
                             "fork server — then bubblewrap)")
    parser.add_argument("--rps", action=argparse.BooleanOptionalAction, default=None,
                        help="resolve `import rps...` to swarmdeck's rps facade (default: when the script imports rps)")
    parser.add_argument("--json", action="store_true", help="print the JSON report (schema swarmdeck.verification/1)")
    parser.add_argument("--html", default=None, metavar="OUT.html", help="write the HTML report there")


def _progress(total_runs: int):  # type: ignore[no-untyped-def]
    if not sys.stderr.isatty():
        return None, lambda: None
    from tqdm import tqdm

    bar = tqdm(total=total_runs, unit="run", desc="verifying", file=sys.stderr, leave=False)
    return (lambda p: bar.update(1)), bar.close


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.cli import UsageError
    from swarmdeck.console.cli.run import check_run_arguments
    from swarmdeck.console.jobs.confinement import ConfinementUnavailable, JailConfig, SandboxLimits
    from swarmdeck.console.jobs.executors import LocalPoolExecutor, RayExecutor
    from swarmdeck.console.jobs.report_html import render_html
    from swarmdeck.console.jobs.verification import REJECTED, VerificationConfig, verify

    check_run_arguments(args.robots, args.duration, seed=args.seed)
    if args.runs < 1:
        raise UsageError(f"--runs must be >= 1, got {args.runs}")
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be >= 1, got {args.workers}")
    try:
        limits = SandboxLimits(tick_s=args.tick_budget, wall_s=max(600.0, 20 * args.duration))
        config = VerificationConfig(n_robots=args.robots, duration=args.duration, runs=args.runs, seed=args.seed,
                                    bypass_threshold=args.bypass_threshold, limits=limits, trusted=args.trusted,
                                    rps=args.rps, jail=JailConfig(order=(args.jail,) if args.jail else JailConfig().order,
                                                                   allow_no_cgroup=args.allow_no_cgroup))
        executor = RayExecutor(args.ray) if args.ray else LocalPoolExecutor(args.workers)
    except (ValueError, RuntimeError) as exc:
        raise UsageError(str(exc)) from exc
    on_progress, close = _progress(2 * args.runs * len(args.scripts))
    try:
        report = verify(args.scripts, config, executor, on_progress=on_progress, entry=args.entry)
    except (ValueError, ConfinementUnavailable) as exc:
        raise UsageError(str(exc)) from exc
    except ConnectionError as exc:
        raise UsageError(f"cannot reach the Ray cluster at {args.ray!r}: {exc}") from exc
    except RuntimeError as exc:  # an executor's infrastructure failed (a Ray worker, a pool process)
        raise UsageError(str(exc)) from exc
    finally:
        close()
    data = report.to_dict()
    if args.html:
        try:
            with open(args.html, "w", encoding="utf-8") as f:
                f.write(render_html(data))
        except OSError as exc:
            raise UsageError(f"cannot write the HTML report {args.html!r}: {exc}") from exc
    if args.json:
        print(json.dumps(data, indent=2))
    else:
        for s in data["scripts"]:
            score = "n/a" if s["safety_score"] is None else f"{s['safety_score']:.4f}"
            print(f"{s['script']}: {s['verdict']} (safety score S = {score} over {args.runs} runs without the barrier)")
            for reason in s["reasons"]:
                print(f"  rejected: {reason}")
            for reason in s["bypass_refused_because"]:
                print(f"  no bypass: {reason}")
        if args.html:
            print(f"report: {args.html}")
    return 1 if report.verdict == REJECTED else 0
