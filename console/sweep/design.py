"""What a sweep runs: parameter axes from ``--param NAME=VALUES``, and the grid or random design over them.

VALUES (one axis):

* ``0.5:2:4`` — 4 values evenly spaced from 0.5 to 2 inclusive (``numpy.linspace``);
* ``log:0.1:10:5`` — 5 values evenly spaced in log from 0.1 to 10 inclusive (``numpy.geomspace``; both > 0);
* ``0.5,1,2`` — these values (numbers, ``true``/``false``, or words for a str parameter); one value alone is fine.

A grid design runs every combination of the axes' values; a random design draws ``samples`` points, each
parameter uniformly in its range (log-uniformly for ``log:``; one of the listed values for a list) from the
design's seed. Every point then runs with each robot count and seed. Pure functions; ValueError
(:class:`DesignError`) naming what is wrong.
"""
from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from swarmdeck.core.errors import SwarmdeckError
from swarmdeck.devices.experiment_params import Value, coerce

#: the most points one sweep's design may have, and the most runs (points × robot counts × seeds); more is refused
#: with the count and a hint
MAX_POINTS = 100_000
MAX_RUNS = 1_000_000
#: digits kept of a computed value (so the table, the cache key and a re-run agree)
_DIGITS = 12


class DesignError(ValueError, SwarmdeckError):
    """A parameter axis or design that cannot run."""


@dataclass(frozen=True)
class Axis:
    """One swept parameter: its name, the values of a grid, and how a random design draws it.

    ``kind``: ``"lin"`` (uniform between ``lo`` and ``hi``), ``"log"`` (log-uniform) or ``"list"`` (one of ``values``).
    """

    name: str
    values: tuple[Value, ...]
    kind: str = "list"
    lo: float = 0.0
    hi: float = 0.0


def _round(x: float) -> float:
    return float(f"{x:.{_DIGITS}g}")


def _number(text: str, where: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise DesignError(f"{where}: {text!r} is not a number") from None
    if not math.isfinite(value):
        raise DesignError(f"{where}: {text!r} is not a finite number")
    return value


def _count(text: str, where: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise DesignError(f"{where}: the count {text!r} is not a whole number") from None
    if n < 1:
        raise DesignError(f"{where}: an empty range ({n} values); give at least 1")
    return n


def scalar(text: str) -> Value:
    """One typed value as the command line and the Submit page read it: ``true``/``false``, an integer, a finite
    number, else the text itself (stripped)."""
    t = text.strip()
    if t.lower() in ("true", "false"):
        return t.lower() == "true"
    try:
        return int(t)
    except ValueError:
        pass
    try:
        value = float(t)
        return value if math.isfinite(value) else t
    except ValueError:
        return t


def parse_axis(spec: str) -> Axis:
    """``NAME=VALUES`` (module docstring) as an :class:`Axis`; DesignError naming the option and what is wrong."""
    where = f"--param {spec!r}"
    name, sep, values = spec.partition("=")
    name = name.strip()
    if not sep or not name:
        raise DesignError(f"{where}: expected NAME=VALUES, e.g. gain=0.5:2:4, gain=0.5,1,2 or gain=log:0.1:10:5")
    if not name.isidentifier():
        raise DesignError(f"{where}: {name!r} is not a parameter name")
    values = values.strip()
    if not values:
        raise DesignError(f"{where}: no values (an empty range)")
    parts = values.split(":")
    if parts[0] == "log":
        if len(parts) != 4:
            raise DesignError(f"{where}: log ranges are log:FIRST:LAST:COUNT, e.g. log:0.1:10:5")
        lo, hi, n = _number(parts[1], where), _number(parts[2], where), _count(parts[3], where)
        if lo <= 0 or hi <= 0:
            raise DesignError(f"{where}: a log range needs FIRST and LAST > 0")
        grid = tuple(_round(v) for v in np.geomspace(lo, hi, n))
        return Axis(name, grid, "log", min(lo, hi), max(lo, hi))
    if len(parts) == 3:
        lo, hi, n = _number(parts[0], where), _number(parts[1], where), _count(parts[2], where)
        grid = tuple(_round(v) for v in np.linspace(lo, hi, n))
        return Axis(name, grid, "lin", min(lo, hi), max(lo, hi))
    if len(parts) != 1:
        raise DesignError(f"{where}: ranges are FIRST:LAST:COUNT or log:FIRST:LAST:COUNT")
    items = [v for v in values.split(",")]
    if any(not v.strip() for v in items):
        raise DesignError(f"{where}: an empty value in the list")
    listed = tuple(dict.fromkeys(scalar(v) for v in items))  # repeated values run once
    return Axis(name, listed, "list")


def check_axes(axes: Sequence[Axis], declared: Mapping[str, Value] | None, script: str) -> tuple[Axis, ...]:
    """The axes with their values as the declared parameters' types; DesignError for a parameter the script does
    not declare (naming the declared ones), a parameter given twice, or a value of the wrong kind."""
    seen: set[str] = set()
    out = []
    declared = declared or {}
    for axis in axes:
        if axis.name in seen:
            raise DesignError(f"--param {axis.name} is given twice")
        seen.add(axis.name)
        if axis.name not in declared:
            listed = ", ".join(f"{k}={v!r}" for k, v in declared.items()) or "none (it calls no params(...))"
            raise DesignError(f"--param {axis.name}: {script} does not declare a parameter {axis.name!r} "
                              f"(it declares: {listed})")
        try:
            values = tuple(coerce(axis.name, declared[axis.name], v) for v in axis.values)
        except ValueError as exc:
            raise DesignError(f"--param {axis.name}: {exc}") from None
        if axis.kind != "list" and isinstance(declared[axis.name], (bool, str)):
            raise DesignError(f"--param {axis.name}: a range needs a number parameter (its default is "
                              f"{declared[axis.name]!r}); list its values instead")
        out.append(Axis(axis.name, tuple(dict.fromkeys(values)), axis.kind, axis.lo, axis.hi))
    return tuple(out)


def parse_counts(text: str | None, what: str) -> tuple[int | None, ...]:
    """``--robots 10,20`` (or a range ``10:50:5``) as robot counts; ``(None,)`` without it (the script's own)."""
    if text is None:
        return (None,)
    axis = parse_axis(f"{what}={text}")
    counts = []
    for v in axis.values:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not float(v).is_integer() or v < 1:
            raise DesignError(f"--{what} {text!r}: {v!r} is not a positive whole number")
        counts.append(int(v))
    return tuple(dict.fromkeys(counts))


def grid_points(axes: Sequence[Axis]) -> list[dict[str, Value]]:
    """Every combination of the axes' values, the first axis slowest (one point with no axis)."""
    names = [a.name for a in axes]
    return [dict(zip(names, combo, strict=True)) for combo in itertools.product(*(a.values for a in axes))]


def random_points(axes: Sequence[Axis], declared: Mapping[str, Value], samples: int, seed: int) -> list[dict[str, Value]]:
    """``samples`` points drawn from ``numpy.random.default_rng(seed)`` (module docstring), the values as the
    declared types (an int parameter draws whole numbers)."""
    if samples < 1:
        raise DesignError(f"--samples must be >= 1, got {samples}")
    rng = np.random.default_rng(seed)
    points = []
    for _ in range(samples):
        point: dict[str, Value] = {}
        for a in axes:
            if a.kind == "list":
                value: Value = a.values[int(rng.integers(len(a.values)))]
            elif a.kind == "log":
                value = _round(math.exp(rng.uniform(math.log(a.lo), math.log(a.hi))))
            else:
                value = _round(rng.uniform(a.lo, a.hi))
            default = declared[a.name]
            if isinstance(default, int) and not isinstance(default, bool):
                value = int(round(float(value)))
            point[a.name] = coerce(a.name, default, value)
        points.append(point)
    return points


def check_size(axes: Sequence[Axis], design: str, samples: int | None, robots: int, seeds: int) -> int:
    """The number of runs, checked before any point is built: DesignError for more than :data:`MAX_POINTS` points
    (the design's points × the robot counts) or :data:`MAX_RUNS` runs, with the count and a hint."""
    points = (math.prod(len(a.values) for a in axes) if design == "grid" else int(samples or 0)) * robots
    if points > MAX_POINTS:
        hint = ("use --design random --samples M to draw M points instead of every combination, or give fewer "
                "values per --param or --robots" if design == "grid" else "draw fewer --samples or --robots")
        raise DesignError(f"the sweep has {points:,} {design} points (with the robot counts), more than the "
                          f"{MAX_POINTS:,} one sweep may have: {hint}")
    runs = points * seeds
    if runs > MAX_RUNS:
        raise DesignError(f"the sweep has {runs:,} runs ({points:,} points x {seeds} seeds), more than the "
                          f"{MAX_RUNS:,} one sweep may have: fewer points or --seeds")
    return runs
