"""``swarmdeck example NAME``: run one of the built-in examples (modules in swarmdeck.console.cli.examples)."""
from __future__ import annotations

import argparse
import importlib
import pkgutil
from collections.abc import Callable
from typing import Any

from swarmdeck.console.cli import examples as _examples
from swarmdeck.console.cli.run import raise_if_failed, run_headless

NAME = "example"
HELP = "run a built-in example (rendezvous, formation, coverage, ...) and print its results"
ORDER = 10


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="example", metavar="NAME", required=True)
    for info in sorted(pkgutil.iter_modules(_examples.__path__), key=lambda i: i.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{_examples.__name__}.{info.name}")
        p = sub.add_parser(module.NAME, help=module.HELP, description=module.HELP)
        module.add_arguments(p)
        p.set_defaults(_example_main=module.main)


def main(args: argparse.Namespace) -> int:
    return int(args._example_main(args) or 0)


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
