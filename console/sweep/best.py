"""The best point of a finished sweep by one metric: what the portal promotes to the arena (issue 31.2).

A point (one set of parameter values and one robot count) qualifies when every one of its runs finished ``ok``
and its runs give the metric a value; the best is the lowest or highest mean over its seeds (ties: the first in
the table's order). Means are :func:`~.summary.mean_ci`'s. Pure functions over the plan and the tidy rows.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from swarmdeck.console.sweep.campaign import Plan
from swarmdeck.console.sweep.runs import BUILTIN, METRIC_PREFIX
from swarmdeck.console.sweep.summary import summarise

#: which way is better for each built-in metric (script metrics need it said)
BUILTIN_GOALS: dict[str, str] = {"contacts": "min", "min_distance": "max", "barrier_interventions": "min",
                                 "coverage_cost_H": "min", "time_to_goal": "min"}
GOALS = ("min", "max")


@dataclass(frozen=True)
class Objective:
    """What "best" means: the table's column (a built-in metric, or ``metric_NAME`` for a script's) and the goal."""

    column: str
    goal: str

    def to_dict(self) -> dict[str, str]:
        return {"metric": self.column, "goal": self.goal}


@dataclass(frozen=True)
class BestPoint:
    """The winning point: its index, robot count, the script's parameter values for it (what the runs got;
    None when the script declares none), the metric's mean and how many runs it is over."""

    point: int
    robots: int | None
    params: dict[str, Any] | None
    mean: float
    runs: int

    def describe(self, objective: Objective) -> str:
        """``gain=0.5 robots=6: min_distance mean 0.213 over 3 runs``."""
        shown = [f"{k}={v}" for k, v in (self.params or {}).items() if k != "robots"]
        if self.robots is not None:
            shown.append(f"robots={self.robots}")
        return f"{' '.join(shown) or 'the defaults'}: {objective.column} mean {self.mean:.6g} over {self.runs} runs"


def objective(metric: Any, goal: Any = None) -> Objective:
    """The objective from a metric name (``min_distance``, or a script metric ``error`` / ``metric_error``) and a
    goal (``min`` | ``max``; None: the built-in metric's own, required for a script's); ValueError naming what is
    wrong."""
    if not isinstance(metric, str) or not metric:
        raise ValueError(f"the metric must be a name (a built-in one: {', '.join(BUILTIN)}; or one the script "
                         f"records), got {metric!r}")
    column = metric if metric in BUILTIN or metric.startswith(METRIC_PREFIX) else METRIC_PREFIX + metric
    if not column[len(METRIC_PREFIX):].isidentifier() and column not in BUILTIN:
        raise ValueError(f"{metric!r} is not a metric name (an identifier)")
    if goal is None:
        if column not in BUILTIN_GOALS:
            raise ValueError(f"say whether a lower or a higher {metric} is better (goal min or max)")
        goal = BUILTIN_GOALS[column]
    if goal not in GOALS:
        raise ValueError(f"the goal must be min or max, got {goal!r}")
    return Objective(column, str(goal))


def best_point(the_plan: Plan, rows: Sequence[dict[str, Any]], wanted: Objective) -> BestPoint | None:
    """The best point of the finished ``rows`` (the plan's order) by ``wanted``; None when no point qualifies."""
    names = [a.name for a in the_plan.axes]
    column = f"{wanted.column}_mean"
    best: dict[str, Any] | None = None
    for entry in summarise(rows, names):
        value = entry.get(column)
        if value is None or entry["failed"]:
            continue
        if best is None or (value < best[column] if wanted.goal == "min" else value > best[column]):
            best = entry
    if best is None:
        return None
    run = next(r for r in the_plan.runs if r.point == best["point"] and r.robots == best["robots"])
    params = run.task.params
    return BestPoint(point=int(best["point"]), robots=None if best["robots"] is None else int(best["robots"]),
                     params=None if params is None else dict(params), mean=float(best[column]),
                     runs=int(best["runs"]))
