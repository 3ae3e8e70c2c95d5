"""Shared command-line plumbing of the built-in examples."""
from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from typing import Any

from swarmdeck.console.cli import UsageError


def add_run_arguments(parser: argparse.ArgumentParser, robots: int, duration: float) -> None:
    """--robots, --duration, --seed and --no-safety with this example's defaults."""
    parser.add_argument("--robots", type=int, default=robots, metavar="N", help=f"number of robots (default {robots})")
    parser.add_argument("--duration", type=float, default=duration, metavar="S", help=f"simulated seconds (default {duration:g})")
    parser.add_argument("--seed", type=int, default=None, help="seed for the random initial conditions")
    parser.add_argument("--no-safety", action="store_true", help="run without the safety barrier")


def check_seed(seed: int | None) -> None:
    """UsageError unless ``--seed`` is None or a non-negative integer (what numpy's generators take)."""
    if seed is not None and seed < 0:
        raise UsageError(f"--seed must be a non-negative integer, got {seed}")


def check_run_arguments(robots: int | None, duration: float | None, min_robots: int = 1, what: str = "",
                        seed: int | None = None) -> None:
    """UsageError unless ``--robots`` is >= ``min_robots``, ``--duration`` a finite number > 0 and
    ``--seed`` non-negative (None: not given)."""
    check_seed(seed)
    if robots is not None and robots < min_robots:
        raise UsageError(f"--robots must be >= {min_robots}{' for ' + what if what else ''}, got {robots}")
    if duration is not None and not (math.isfinite(duration) and duration > 0):
        raise UsageError(f"--duration must be a finite number of seconds > 0, got {duration}")


def run_headless(experiment: Callable[..., Any] | str, args: argparse.Namespace, min_robots: int = 1,
                 what: str = "", **kw: Any) -> Any:
    """Run ``experiment`` (a callable or a script path) with the common arguments; print the reports.

    Returns the :class:`~swarmdeck.devices.runner.RunResult`. Raises UsageError when
    the run cannot start (bad script file, too many robots) or when the experiment raised
    (one line naming the script's line; the reports are printed first, the robots were stopped).
    """
    from swarmdeck.devices.runner import ScriptError, progress_bar, run_experiment

    check_run_arguments(args.robots, args.duration, min_robots, what, args.seed)
    on_step, close = progress_bar(args.duration)
    try:
        result = run_experiment(experiment, n_robots=args.robots, duration=args.duration, seed=args.seed,
                                safety=not args.no_safety, on_step=on_step, **kw)
    except (ScriptError, ValueError) as exc:
        raise UsageError(str(exc)) from exc
    finally:
        close()
    return result


def raise_if_failed(result: Any) -> None:
    """After the reports are printed: a run whose experiment raised is a UsageError (exit 2)."""
    if result.error_line:
        raise UsageError(f"the experiment raised, robots were stopped: {result.error_line}")


def run_example(experiment: Callable[..., Any], args: argparse.Namespace, min_robots: int = 1, what: str = "") -> int:
    """Run ``experiment(arena)`` headless on the simulated arena; print the report and its results.

    ``min_robots``: the fewest robots the example works with (``what`` names it in the error).
    """
    result = run_headless(experiment, args, min_robots, what)
    for report in result.reports:
        print(report)
    for name, value in (result.returned or {}).items():
        print(f"{name}: {value:.4f}" if isinstance(value, float) else f"{name}: {value}")
    raise_if_failed(result)
    return 0
