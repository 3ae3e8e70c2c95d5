"""One run of a sweep: its key (what it reproduces from), the sandboxed run, and its row of the table.

A run is verification's run (:func:`~swarmdeck.console.sandbox.verification.run_task_plant`: the same sandbox,
disturbances and seeding) of the script at one point of the design — its parameter values reach
``swarmdeck.devices.params()`` in the jail — with one robot count and one seed, with the barrier on (as the arena
runs it) unless the sweep asks for raw runs. :func:`run_point` is what an executor runs in its worker (a local
process, a Ray worker); its row is JSON-ready and a pure function of the run (no timings: they go beside it).
"""
from __future__ import annotations

from dataclasses import dataclass
from importlib import metadata
from typing import Any

import numpy as np

from swarmdeck.console.sandbox.verification import RunTask, run_task_plant, user_message
from swarmdeck.core.bounds import Bounds
from swarmdeck.coverage.density import GaussianMixture
from swarmdeck.coverage.geometry import GeometryConfig, coverage_geometry
from swarmdeck.devices.experiment_params import Value

#: the built-in metrics of every row, in the table's order (units: count, m, robot-steps, m^4 (H of the uniform
#: density over the arena at the run's end), s)
BUILTIN = ("contacts", "min_distance", "barrier_interventions", "coverage_cost_H", "time_to_goal")
#: a script metric's column: this prefix and its name (``record_metrics(error=…)`` → ``metric_error``)
METRIC_PREFIX = "metric_"
#: the metric a script records to fill ``time_to_goal`` (s: when its goal was reached)
TIME_TO_GOAL = "time_to_goal"


@dataclass(frozen=True)
class SweepRun:
    """One run of a sweep: ``point`` (index in the design), its ``params`` (name, value) in the axes' order,
    ``robots`` (None: the script's own count), ``seed``, the sandboxed ``task`` and the ``key`` it is cached under;
    ``capsule``: where to write the run's capsule zip, recorded (``swarmdeck sweep --capsules``; None: not recorded)."""

    key: str
    point: int
    params: tuple[tuple[str, Value], ...]
    robots: int | None
    seed: int
    task: RunTask
    capsule: str | None = None


def swarmdeck_version() -> str:
    """The installed swarmdeck's version (part of every run's key: another version runs again)."""
    try:
        return metadata.version("swarmdeck")
    except metadata.PackageNotFoundError:
        return "unknown"


def coverage_cost(positions: np.ndarray, bounds: Bounds) -> float | None:
    """Locational cost H (m^4 per unit density) of ``positions`` (N, 2) m under the uniform density on ``bounds``
    (None when the diagram cannot be built)."""
    geom = coverage_geometry(positions, GaussianMixture(floor=1.0), GeometryConfig(bounds=bounds))
    return round(geom.cost_H, 9) if geom.ok else None


def run_point(run: SweepRun) -> dict[str, Any]:
    """Run ``run`` in the sandbox and give its row: key, point, parameters, robots, seed, status (``ok`` or
    ``failed``), error, ended_by, time_s, the built-in metrics (:data:`BUILTIN`) and the script's (prefixed
    :data:`METRIC_PREFIX`); ``cpu_s`` beside them (a timing, not part of the table)."""
    if run.capsule is not None:  # recorded, and its capsule written (console/sweep/capsules.py)
        from swarmdeck.console.sweep.capsules import run_recorded

        done = run_recorded(run.task, run.capsule, sweep_key=run.key)
        result, plant = done["result"], done["plant"]
    else:
        result, plant = run_task_plant(run.task)
    metrics = dict(result.get("metrics") or {})
    filt = result.get("safety_filter") or {}
    contacts = result.get("contacts")
    h = None
    if plant is not None and plant.arena is not None:
        h = coverage_cost(plant.arena.backend.true_poses[:, :2], run.task.config.bounds)
    error = user_message(result["error"], run.task.bundle)
    row: dict[str, Any] = {"key": run.key, "point": run.point, **dict(run.params),
                           "robots": result.get("n_robots") if result.get("n_robots") is not None else run.robots,
                           "seed": run.seed, "status": "ok" if error is None else "failed", "error": error,
                           "ended_by": result["ended_by"], "time_s": result.get("time"),
                           "contacts": None if not contacts else int(contacts["count"]),
                           "min_distance": None if result.get("min_distance") is None else round(result["min_distance"], 9),
                           "barrier_interventions": filt.get("interventions"),
                           "coverage_cost_H": h, "time_to_goal": metrics.pop(TIME_TO_GOAL, None)}
    row.update({METRIC_PREFIX + k: v for k, v in sorted(metrics.items())})
    row["cpu_s"] = result.get("cpu_s")
    return row
