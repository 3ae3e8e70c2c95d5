"""``swarmdeck run SCRIPT.py``: run a user experiment headless on the simulated arena."""
from __future__ import annotations

import argparse
import json
import sys

from swarmdeck.console.cli import UsageError

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


def main(args: argparse.Namespace) -> int:
    from swarmdeck.devices.experiment_runner import ScriptError, progress_bar, run_experiment

    if args.robots is not None and args.robots < 1:
        raise UsageError(f"--robots must be >= 1, got {args.robots}")
    if args.duration is not None and not args.duration > 0:
        raise UsageError(f"--duration must be > 0 s, got {args.duration}")
    on_step, close = progress_bar(args.duration)
    try:
        result = run_experiment(args.script, n_robots=args.robots, duration=args.duration, seed=args.seed,
                                safety=not args.no_safety, on_step=on_step, rps=args.rps)
    except ScriptError as exc:
        raise UsageError(str(exc)) from exc
    except ValueError as exc:  # e.g. too many robots for the arena
        raise UsageError(str(exc)) from exc
    finally:
        close()
    if args.json:
        print(json.dumps({"reports": [r.to_dict() for r in result.reports], "error": result.error}, indent=2))
    else:
        for report in result.reports:
            print(report)
        if isinstance(result.returned, dict):
            for key, value in result.returned.items():
                print(f"{key}: {value}")
    if result.error:
        print("the experiment script raised; robots were stopped:\n" + result.error, file=sys.stderr)
        return 1
    return 0
