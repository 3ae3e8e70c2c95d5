"""The sweep's statistics: mean and confidence interval of a metric over a point's seeds, per point and per value.

The CI of a mean over n runs is Student's t: mean ± t_{(1+c)/2, n−1} · s / √n (s the sample standard deviation);
with one run there is no interval (None). Rows are the tidy table's (:mod:`.runs`); only ``ok`` rows with a value
count. Pure functions.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy.stats import t as student_t

from swarmdeck.console.sweep.runs import BUILTIN, METRIC_PREFIX

CONFIDENCE = 0.95


def mean_ci(values: Sequence[float], confidence: float = CONFIDENCE) -> tuple[float | None, float | None, float | None]:
    """(mean, low, high) of ``values`` (None, None, None when empty; low = high = None with one value)."""
    x = np.asarray([v for v in values if v is not None and math.isfinite(v)], dtype=float)
    if x.size == 0:
        return None, None, None
    mean = float(x.mean())
    if x.size < 2:
        return mean, None, None
    half = float(student_t.ppf(0.5 + confidence / 2, x.size - 1) * x.std(ddof=1) / math.sqrt(x.size))
    return mean, mean - half, mean + half


def metric_columns(rows: Sequence[dict[str, Any]]) -> list[str]:
    """The metrics of the table: the built-in ones, then the script's (sorted) — those some row has a value of."""
    scripts = sorted({k for r in rows for k in r if k.startswith(METRIC_PREFIX)})
    return [m for m in (*BUILTIN, *scripts) if any(r.get(m) is not None for r in rows)]


def summarise(rows: Sequence[dict[str, Any]], names: Sequence[str]) -> list[dict[str, Any]]:
    """One row per point and robot count (in the table's order): its parameters (``names``), ``robots``, ``runs``,
    ``failed``, and for every metric ``M``: ``M_mean``, ``M_ci_low``, ``M_ci_high`` (95 %)."""
    groups: dict[tuple[Any, Any], list[dict[str, Any]]] = {}
    for r in rows:
        groups.setdefault((r["point"], r.get("robots")), []).append(r)
    metrics = metric_columns(rows)
    out = []
    for (point, robots), group in groups.items():
        first = group[0]
        ok = [r for r in group if r["status"] == "ok"]
        entry: dict[str, Any] = {"point": point, **{n: first.get(n) for n in names if n != "robots"},
                                 "robots": robots, "runs": len(group), "failed": len(group) - len(ok)}
        for m in metrics:
            mean, lo, hi = mean_ci([r[m] for r in ok if r.get(m) is not None])
            entry.update({f"{m}_mean": mean, f"{m}_ci_low": lo, f"{m}_ci_high": hi})
        out.append(entry)
    return out


def by_value(rows: Sequence[dict[str, Any]], axis: str, metric: str) -> dict[Any, list[tuple[Any, float, float | None, float | None]]]:
    """For a plot of ``metric`` against parameter ``axis``: per robot count (one series, key None, when ``axis`` is
    ``robots``), sorted (value, mean, low, high) over every ``ok`` run at that value (the other parameters pooled)."""
    series: dict[Any, dict[Any, list[float]]] = {}
    for r in rows:
        if r["status"] == "ok" and r.get(metric) is not None and r.get(axis) is not None:
            group = None if axis == "robots" else r.get("robots")
            series.setdefault(group, {}).setdefault(r[axis], []).append(r[metric])
    out: dict[Any, list[tuple[Any, float, float | None, float | None]]] = {}
    for robots, values in series.items():
        points = []
        for value in sorted(values):
            mean, lo, hi = mean_ci(values[value])
            if mean is not None:
                points.append((value, mean, lo, hi))
        out[robots] = points
    return out
