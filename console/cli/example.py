"""``swarmdeck example NAME``: run one of the built-in examples (modules in swarmdeck.console.cli.examples)."""
from __future__ import annotations

import argparse
import importlib
import pkgutil

from swarmdeck.console.cli import examples as _examples

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
