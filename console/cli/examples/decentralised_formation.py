"""``swarmdeck example decentralised-formation``: the decentralised formation example (see examples/decentralised_formation.py)."""
from __future__ import annotations

import argparse

from swarmdeck.console.cli.example import run_example
from swarmdeck.console.cli.run import add_run_arguments
from swarmdeck.examples import decentralised_formation as _example

NAME = "decentralised-formation"
HELP = _example.__doc__.strip().splitlines()[0]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_run_arguments(parser, robots=6, duration=40.0)


def main(args: argparse.Namespace) -> int:
    return run_example(_example.experiment, args, min_robots=3, what="decentralised formation")
