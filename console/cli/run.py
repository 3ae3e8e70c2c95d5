"""``swarmdeck run SCRIPT.py``: run a user experiment headless on the simulated arena."""
from __future__ import annotations

import argparse
import json
import sys

NAME = "run"
HELP = "run an experiment script headless on the simulated arena and print its report"
ORDER = 20


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("script", help="Python file defining experiment(arena), or an rps-style script that builds Arena()")
    parser.add_argument("--robots", type=int, default=None, metavar="N", help="number of robots (default: the script's, else 6)")
    parser.add_argument("--duration", type=float, default=None, metavar="S", help="stop after S simulated seconds")
    parser.add_argument("--seed", type=int, default=None, help="seed for random initial conditions")
    parser.add_argument("--no-safety", action="store_true", help="run without the barrier-certificate safety filter")
    parser.add_argument("--json", action="store_true", help="print the report as JSON")
    parser.add_argument("--rps", action=argparse.BooleanOptionalAction, default=None,
                        help="resolve `import rps...` to swarmdeck's rps facade (default: when the script imports rps and no rps is installed)")
    parser.add_argument("--sandbox", action="store_true",
                        help="run the script in a confined child process (no network, read-only files, resource limits); "
                             "swarmdeck keeps the simulator and the safety filter")
    parser.add_argument("--trusted", action="store_true",
                        help="with --sandbox: run unconfined (resource limits only) where this machine cannot confine")


def _run_sandboxed(args: argparse.Namespace) -> int:
    from swarmdeck.console.cli import UsageError
    from swarmdeck.console.cli.examples._common import check_run_arguments
    from swarmdeck.console.jobs.confinement import ConfinementUnavailable
    from swarmdeck.console.jobs.plant import ArenaPlant
    from swarmdeck.console.jobs.sandbox import run_sandboxed
    from swarmdeck.devices.arena import Arena
    from swarmdeck.devices.simulator import ArenaConfig

    check_run_arguments(args.robots, args.duration, seed=args.seed)
    config = ArenaConfig(seed=args.seed)

    def make_plant(n, initial):  # type: ignore[no-untyped-def]
        return ArenaPlant(Arena(n, initial_conditions=initial, config=config, safety=not args.no_safety,
                                duration=args.duration))

    try:
        outcome = run_sandboxed(args.script, make_plant, n_robots=args.robots, duration=args.duration, rps=args.rps,
                                trusted=args.trusted)
    except (ConfinementUnavailable, ValueError) as exc:
        raise UsageError(str(exc)) from exc
    if outcome.log:
        print(outcome.log, end="" if outcome.log.endswith("\n") else "\n")
    report = outcome.plant.arena.report() if outcome.plant is not None else None
    if args.json:
        print(json.dumps({"reports": [report.to_dict()] if report else [], "error": outcome.error,
                          "error_line": outcome.error_line, "ended_by": outcome.ended_by,
                          "overruns": outcome.overruns}, indent=2))
    elif report is not None:
        print(report)
    if outcome.error_line:
        raise UsageError(f"the sandboxed script ended, robots were stopped: {outcome.error_line}")
    return 0


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.cli.examples._common import raise_if_failed, run_headless

    if args.sandbox:
        return _run_sandboxed(args)
    result = run_headless(args.script, args, rps=args.rps)
    if args.json:
        print(json.dumps({"reports": [r.to_dict() for r in result.reports], "error": result.error,
                          "error_line": result.error_line, "notes": result.notes,
                          "interrupted": result.interrupted}, indent=2))
    else:
        for report in result.reports:
            print(report)
        for note in result.notes:
            print(f"note: {note}")
        if isinstance(result.returned, dict):
            for key, value in result.returned.items():
                print(f"{key}: {value}")
    if result.interrupted:
        print("swarmdeck run: interrupted (robots stopped); the report covers the run so far", file=sys.stderr)
        return 130
    raise_if_failed(result)
    return 0
