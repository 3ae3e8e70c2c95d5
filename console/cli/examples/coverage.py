"""``swarmdeck example coverage``: the coverage example on the simulated arena (see examples/coverage.py).

    swarmdeck example coverage [--robots N] [--density moving|image:PATH|letter:TEXT]
                               [--duration S] [--law tvd-d1] [--kappa K] [--no-safety]
    swarmdeck example coverage --s1          # scenario S1 of REFERENCE.md §5, all laws

This module is the command line only: choosing the density and the law, and printing the H(t)
summary; the experiment itself is :func:`swarmdeck.examples.coverage.coverage_experiment`.
"""
from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from swarmdeck.console.cli import UsageError
from swarmdeck.console.cli.run import add_run_arguments, check_run_arguments, raise_if_failed, run_headless
from swarmdeck.core.bounds import Bounds
from swarmdeck.coverage import CoverageConfig, Density, image_density, letter_image, moving_density
from swarmdeck.examples.coverage import coverage_experiment

NAME = "coverage"
HELP = "coverage control of a moving density (TVD-D1) through the safety filter; --s1 prints the S1 table"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_run_arguments(parser, robots=12, duration=30.0)
    parser.add_argument("--density", default="moving", metavar="SPEC",
                        help="moving (default; three bumps that orbit, breathe and fade), "
                             "image:PATH (dark pixels of a grey image attract robots) or letter:TEXT")
    parser.add_argument("--law", default="tvd-d1",
                        help="lloyd, lloyd-ff, tvd-d1 (default), tvd-d2, … (tvd-c is not offered here)")
    parser.add_argument("--kappa", type=float, default=1.0, help="feedback gain κ in 1/s (default 1)")
    parser.add_argument("--rows", type=int, default=10, help="rows of the H(t) summary (default 10)")
    parser.add_argument("--s1", action="store_true",
                        help="run scenario S1 (9 robots, no barrier) for every law and print the table")


def make_density(spec: str, bounds: Bounds) -> Density:
    """The density named by ``--density``; raises UsageError for a bad spec or file."""
    kind, _, arg = spec.partition(":")
    try:
        if kind == "moving" and not arg:
            return moving_density(bounds)
        if kind == "image" and arg:
            return image_density(arg, bounds)
        if kind == "letter" and arg:
            return image_density(letter_image(arg), bounds)
    except ValueError as exc:
        raise UsageError(f"--density {spec}: {exc}") from exc
    raise UsageError(f"--density must be moving, image:PATH or letter:TEXT, got {spec!r}")


def _summary(res: dict[str, Any], rows: int) -> list[str]:
    t, h, d = res["t"], res["H"], res["distance"]
    lines = ["| t (s) | H / ∫φ | mean ‖p − c‖ (m) |", "| ---: | ---: | ---: |"]
    if t.size:
        for k in np.unique(np.linspace(0, t.size - 1, max(2, rows)).round().astype(int)):
            lines.append(f"| {t[k]:.1f} | {h[k]:.5f} | {d[k]:.4f} |")
        lines.append(f"| mean | {h.mean():.5f} | {d.mean():.4f} |")
    return lines


def _run_s1() -> int:
    from swarmdeck.coverage.scenario import format_s1_table, run_s1_all

    print("scenario S1 (REFERENCE.md §5): 9 robots, moving Gaussian, κ = 1, dt = 0.033 s, 40 s, "
          "no barrier, no saturation", flush=True)
    print(format_s1_table(run_s1_all(progress=True)))
    return 0


def main(args: argparse.Namespace) -> int:
    if args.s1:
        return _run_s1()
    from swarmdeck.coverage import parse_law
    from swarmdeck.devices import ArenaConfig

    check_run_arguments(args.robots, args.duration, seed=args.seed)
    try:
        family, _ = parse_law(args.law)
        CoverageConfig(law=args.law, kappa=args.kappa)
    except ValueError as exc:
        raise UsageError(str(exc)) from exc
    if family == "tvd-c":
        raise UsageError("tvd-c is a centralised reference law, not offered here")
    density = make_density(args.density, ArenaConfig().bounds)
    result = run_headless(lambda arena: coverage_experiment(arena, density, args.law, args.kappa), args)
    for report in result.reports:
        print(report)
    raise_if_failed(result)
    res = result.returned
    print(f"coverage: law {args.law}, κ = {args.kappa:g}, density {args.density}, "
          f"{args.robots} robots, {args.duration:g} s")
    for line in _summary(res, args.rows):
        print(line)
    for w in res["warnings"]:
        print(f"warning: {w}")
    if res["failures"]:
        print(f"coverage step failed on {res['failures']} tick(s); robots were stopped then")
    return 0
