"""Shared command-line plumbing of the built-in examples."""
from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from typing import Any

from swarmdeck.console.cli import UsageError


def add_run_arguments(parser: argparse.ArgumentParser, robots: int, duration: float) -> None:
    """--robots, --duration, --seed and --no-safety with this example's defaults."""
    parser.add_argument("--robots", type=int, default=robots, metavar="N", help=f"number of robots (default {robots})")
    parser.add_argument("--duration", type=float, default=duration, metavar="S", help=f"simulated seconds (default {duration:g})")
    parser.add_argument("--seed", type=int, default=None, help="seed for the random initial conditions")
    parser.add_argument("--no-safety", action="store_true", help="run without the safety barrier")


def run_example(experiment: Callable[..., Any], args: argparse.Namespace) -> int:
    """Run ``experiment(arena)`` headless on the simulated arena; print the report and its results."""
    from swarmdeck.devices.experiment_runner import progress_bar, run_experiment

    if args.robots < 1:
        raise UsageError(f"--robots must be >= 1, got {args.robots}")
    if not args.duration > 0:
        raise UsageError(f"--duration must be > 0 s, got {args.duration}")
    on_step, close = progress_bar(args.duration)
    try:
        result = run_experiment(experiment, n_robots=args.robots, duration=args.duration, seed=args.seed,
                                safety=not args.no_safety, on_step=on_step)
    except ValueError as exc:
        raise UsageError(str(exc)) from exc
    finally:
        close()
    for report in result.reports:
        print(report)
    for name, value in (result.returned or {}).items():
        print(f"{name}: {value:.4f}" if isinstance(value, float) else f"{name}: {value}")
    if result.error:
        print(result.error, file=sys.stderr)
        return 1
    return 0
