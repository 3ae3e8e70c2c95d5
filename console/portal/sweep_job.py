"""Sweep jobs (issue 31): a parameter sweep submitted to the portal as ONE job, run in simulation on the lab's
verification executors (the local pool or Ray of ``swarmdeck server``; every run sandboxed, as verification's).

A sweep job goes ``awaiting verification`` → ``verifying`` (its runs) → ``done`` | ``failed`` (or ``cancelled``): it
never enters the arena queue. Its runs' CPU is charged to the researcher's daily verification CPU limit
(:mod:`.quotas`). Its outputs (:func:`swarmdeck.console.sweep.outputs.write_outputs`) are in the job's folder under
``sweep/`` and are downloaded by the names of :data:`SWEEP_FILES` (``plots/NAME.png`` for the plots).

**Request** (JSON object; :func:`parse_request`), the same words as ``swarmdeck sweep``: ``name`` (optional, 1-100
printable characters), ``params`` (list of ``NAME=VALUES`` strings as ``--param`` takes them), ``robots`` (an
integer, or ``N[,N...]`` / ``a:b:n`` text as ``--robots``; required, each count 1 … the fleet), ``seeds`` (runs per
point, ≥ 1), ``seed`` (the first seed and the random design's seed, ≥ 0), ``design`` (``grid`` | ``random``),
``samples`` (points of a random design), ``duration`` (simulated s per run, > 0, at most the portal's maximum),
``no_barrier`` (run raw), ``promote`` (optional ``{"metric": NAME, "goal": "min"|"max"}``: when the sweep is done,
its best point by that metric — :func:`swarmdeck.console.sweep.best.best_point` — is submitted as a normal arena job
of the same researcher, with the point's parameter values and robot count; it is verified and queued like any job;
``goal`` may be left out for a built-in metric). Unknown keys are refused. The CLI's refusals (an undeclared parameter, an empty range, too
many points) are :class:`~.errors.BadInput` (422) with the CLI's message; a sweep of more than :data:`MAX_RUNS` runs
is refused too.
"""
from __future__ import annotations

import csv
import io
import math
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from swarmdeck.console.portal.errors import BadInput
from swarmdeck.console.portal.submission import Limits, json_object
from swarmdeck.console.sandbox.bundle import ScriptBundle
from swarmdeck.console.sandbox.verification import VerificationConfig
from swarmdeck.console.sweep.best import Objective, objective
from swarmdeck.console.sweep.campaign import Plan, SweepResult, SweepSpec, plan, run_sweep
from swarmdeck.console.sweep.design import DesignError, parse_axis, parse_counts

REQUEST_KEYS = ("name", "params", "robots", "seeds", "seed", "design", "samples", "duration", "no_barrier", "promote")
#: the most runs one portal sweep may have (points × robot counts × seeds); the daily CPU limit applies as well
MAX_RUNS = 2000
#: the folder of a sweep job's outputs inside its job folder
SWEEP_DIR = "sweep"
#: download name -> (path under ``sweep/``, what it is)
SWEEP_FILES: dict[str, tuple[str, str]] = {
    "sweep-report.html": ("report.html", "the sweep's report: summary with CIs, plots, failures (HTML)"),
    "results.csv": ("results.csv", "the sweep's table: one row per run (CSV)"),
    "results.parquet": ("results.parquet", "the sweep's table (Parquet)"),
    "summary.csv": ("summary.csv", "per point and robot count: mean and 95 % CI of every metric (CSV)"),
    "sweep.json": ("sweep.json", "what the sweep ran (JSON)"),
}
#: the headers a sweep's report is served with inline: no script, its own origin; its plots and tables load
REPORT_HEADERS: dict[str, str] = {"Content-Security-Policy": "sandbox; default-src 'none'; img-src 'self'; "
                                                             "style-src 'unsafe-inline'"}
#: a plot's download name (``plots/METRIC-vs-PARAM.png``, as report.html links it)
PLOT_RE = re.compile(r"^plots/[A-Za-z0-9_][A-Za-z0-9_.-]{0,150}\.png$")


@dataclass(frozen=True)
class SweepRequest:
    """A checked sweep request (module docstring); ``robots`` is the ``--robots`` text, ``counts`` its values."""

    name: str
    params: tuple[str, ...]
    robots: str
    counts: tuple[int, ...]
    seeds: int = 1
    seed: int = 0
    design: str = "grid"
    samples: int | None = None
    duration: float = 30.0
    no_barrier: bool = False
    promote: Objective | None = None  # the best point by this goes to the arena when the sweep is done

    def to_dict(self) -> dict[str, Any]:
        """The request as stored with the job (and shown on the API): :func:`parse_request` reads it back."""
        return {"name": self.name, "params": list(self.params), "robots": self.robots, "seeds": self.seeds,
                "seed": self.seed, "design": self.design, "samples": self.samples, "duration": self.duration,
                "no_barrier": self.no_barrier, "promote": None if self.promote is None else self.promote.to_dict()}


def _int(data: dict[str, Any], key: str, default: int | None, least: int) -> int | None:
    value = data.get(key, default)
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int) or value < least:
        raise BadInput(f"{key} must be an integer >= {least}, got {value!r}", key)
    return value


def parse_request(data: Any, limits: Limits, default_name: str = "sweep") -> SweepRequest:
    """The checked request from JSON text or an object; :class:`BadInput` (422) naming the key."""
    data = json_object(data, "sweep")
    unknown = sorted(set(data) - set(REQUEST_KEYS))
    if unknown:
        raise BadInput(f"unknown sweep key {unknown[0]!r} (known: {', '.join(REQUEST_KEYS)})", unknown[0])
    name = data.get("name", default_name)
    if not isinstance(name, str) or not 1 <= len(name.strip()) <= 100 or not name.isprintable():
        raise BadInput("name must be 1-100 printable characters", "name")
    params = data.get("params", [])
    if not isinstance(params, list) or not all(isinstance(p, str) for p in params):
        raise BadInput("params must be a list of NAME=VALUES strings (as swarmdeck sweep --param takes them)", "params")
    robots = data.get("robots")
    if robots is None:
        raise BadInput("the sweep needs 'robots' (a count, or N[,N...] as swarmdeck sweep --robots)", "robots")
    if isinstance(robots, int) and not isinstance(robots, bool):
        robots = str(robots)
    if not isinstance(robots, str):
        raise BadInput(f"robots must be a count or N[,N...] text, got {robots!r}", "robots")
    try:
        counts = parse_counts(robots, "robots")
    except DesignError as exc:
        raise BadInput(str(exc), "robots") from None
    too_many = [c for c in counts if c is None or c > limits.fleet]
    if too_many:
        raise BadInput(f"robots must be between 1 and {limits.fleet} (the robots this arena has), got {too_many[0]}",
                       "robots")
    duration = data.get("duration", 30.0)
    if isinstance(duration, bool) or not isinstance(duration, (int, float)) or not math.isfinite(duration):
        raise BadInput(f"duration must be a number of seconds, got {duration!r}", "duration")
    if not 0 < duration <= limits.max_duration:
        raise BadInput(f"duration must be > 0 and at most {limits.max_duration:g} s, got {duration:g}", "duration")
    design = data.get("design", "grid")
    if design not in ("grid", "random"):
        raise BadInput(f"design must be grid or random, got {design!r}", "design")
    no_barrier = data.get("no_barrier", False)
    if not isinstance(no_barrier, bool):
        raise BadInput(f"no_barrier must be true or false, got {no_barrier!r}", "no_barrier")
    promote = data.get("promote")
    if promote is not None:
        if not isinstance(promote, dict) or set(promote) - {"metric", "goal"}:
            raise BadInput('promote must be an object {"metric": NAME, "goal": "min" or "max"}', "promote")
        try:
            promote = objective(promote.get("metric"), promote.get("goal"))
        except ValueError as exc:
            raise BadInput(f"promote: {exc}", "promote") from None
    return SweepRequest(name=name.strip(), params=tuple(params), robots=robots, promote=promote,
                        counts=tuple(int(c) for c in counts if c is not None),
                        seeds=int(_int(data, "seeds", 1, 1) or 1), seed=int(_int(data, "seed", 0, 0) or 0),
                        design=str(design), samples=_int(data, "samples", None, 1), duration=float(duration),
                        no_barrier=no_barrier)


def sweep_spec(request: SweepRequest, bundle: ScriptBundle, base: VerificationConfig | None = None) -> SweepSpec:
    """The sweep's :class:`SweepSpec` on ``base`` (the lab's sandbox, jail, obstacles; its duration, robots and
    poses are the request's): DesignError / ValueError as ``swarmdeck sweep`` refuses it."""
    config = replace(base if base is not None else VerificationConfig(), duration=request.duration, n_robots=None,
                     initial_poses=None)
    axes = tuple(parse_axis(p) for p in request.params)
    return SweepSpec(bundle, axes, seeds=request.seeds, first_seed=request.seed, robots=request.counts,
                     design=request.design, samples=request.samples, design_seed=request.seed, config=config,
                     barrier=not request.no_barrier)


def check_sweep(request: SweepRequest, bundle: ScriptBundle) -> Plan:
    """The sweep's plan, or :class:`BadInput` (422, field ``params``) with ``swarmdeck sweep``'s message (an
    undeclared parameter, an empty range, too many points), or naming :data:`MAX_RUNS`."""
    try:
        the_plan = plan(sweep_spec(request, bundle))
    except ValueError as exc:  # DesignError is a ValueError
        raise BadInput(str(exc), "params") from None
    if len(the_plan.runs) > MAX_RUNS:
        raise BadInput(f"the sweep has {len(the_plan.runs)} runs; a portal sweep may have at most {MAX_RUNS}: "
                       "sweep fewer points or seeds, or run it on your machine (swarmdeck sweep)", "params")
    return the_plan


def run_job(request: SweepRequest, bundle: ScriptBundle, base: VerificationConfig, folder: Path, executor: Any,
            cancel: Any) -> SweepResult:
    """Run the sweep into ``folder/sweep/`` on ``executor`` (:func:`~swarmdeck.console.sweep.campaign.run_sweep`:
    SweepIncomplete when cancelled or the executor failed, ConfinementUnavailable, DesignError)."""
    return run_sweep(sweep_spec(request, bundle, base), folder / SWEEP_DIR, executor, cancel=cancel)


def results(folder: Path) -> dict[str, Any] | None:
    """A sweep job's results in short, from its folder: ``{"runs", "failed", "summary", "report"}`` (``summary``:
    summary.csv's rows as text cells); None before the sweep wrote its table."""
    out = folder / SWEEP_DIR
    try:
        rows = list(csv.DictReader(io.StringIO((out / "results.csv").read_text(encoding="utf-8"))))
        summary = list(csv.DictReader(io.StringIO((out / "summary.csv").read_text(encoding="utf-8"))))
    except (OSError, ValueError, csv.Error):
        return None
    return {"runs": len(rows), "failed": sum(1 for r in rows if r.get("status") != "ok"), "summary": summary,
            "report": "sweep-report.html"}


def file_path(folder: Path, name: str) -> Path | None:
    """The path of a sweep job's download ``name`` (a key of :data:`SWEEP_FILES` or ``plots/NAME.png``), None for
    another name."""
    if name in SWEEP_FILES:
        return folder / SWEEP_DIR / SWEEP_FILES[name][0]
    if PLOT_RE.match(name) and ".." not in name:
        return folder / SWEEP_DIR / name
    return None
