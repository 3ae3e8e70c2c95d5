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


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.cli.examples._common import raise_if_failed, run_headless

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
