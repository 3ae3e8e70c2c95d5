"""A sweep from start to end: plan the runs, skip those already done, run the rest on an executor, write the outputs.

The output folder (``-o DIR``)::

    DIR/sweep.json          what was asked (script, axes, design, seeds, robots, config) and the plan's size
    DIR/runs/KEY.json       one finished run's row (the cache: a run whose key is here is not run again)
    DIR/results.csv         the tidy table: one row per run (always)
    DIR/results.parquet     the same table (with pyarrow: ``pip install 'swarmdeck[sweep]'``)
    DIR/summary.csv         per point and robot count: runs, failures, mean and 95 % CI of every metric
    DIR/plots/*.png         each metric against each swept parameter, with its CI band
    DIR/report.html         the summary, the plots and the failures, one page
    DIR/capsules/KEY.zip    with --capsules: each run recorded, as a capsule (``swarmdeck run KEY.zip`` reproduces it)

**Resumable.** Each run's row is written (atomically) the moment it finishes, keyed by
:func:`~swarmdeck.console.recording.capsule.run_key` (script files, parameter values, robot count, seed, configuration,
swarmdeck's version). An interrupted sweep (Ctrl-C, a cancel, a Ray cluster gone, a killed process) continues
where it stopped when the same command runs again; a changed script or configuration runs anew. Runs cancelled
half-way leave nothing behind. A run whose script fails is a ``failed`` row with its error (cached: it fails the
same way again) and the sweep goes on; a run that failed for a reason of the machine (:data:`TRANSIENT`: the jail did
not start in time, the wall-time budget) is a row of this table but is run again by the next invocation.

**Deterministic.** A run is a pure function of its task (verification's seeding), and the table is written in the
plan's order, so any executor — serial, the local pool, Ray — gives the same table, byte for byte.
"""
from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from swarmdeck.console.recording.capsule import run_key
from swarmdeck.console.sandbox.bundle import ScriptBundle
from swarmdeck.console.sandbox.verification import RunTask, VerificationConfig, compile_check
from swarmdeck.console.sweep.capsules import CAPSULES_DIR
from swarmdeck.console.sweep.design import Axis, DesignError, check_axes, check_size, grid_points, random_points
from swarmdeck.console.sweep.runs import SweepRun, run_point, swarmdeck_version
from swarmdeck.core.errors import SwarmdeckError
from swarmdeck.devices.experiment_params import ParamError, Value, declared_in_source

#: columns of every row; a script parameter may not be called so (``robots`` is the robot count: see :class:`SweepSpec`)
#: how a run may end for a reason of the machine rather than the script (the jail did not start in time, the wall-time
#: budget on a loaded machine): such a row is in this sweep's table but not cached, so running the sweep again retries it
TRANSIENT = frozenset({"boot", "wall"})
RESERVED = frozenset({"key", "point", "seed", "status", "error", "ended_by", "time_s", "contacts", "min_distance",
                      "barrier_interventions", "coverage_cost_H", "time_to_goal", "cpu_s"})


@dataclass(frozen=True)
class SweepSpec:
    """What a sweep runs.

    ``axes``: the swept parameters (:func:`~swarmdeck.console.sweep.design.parse_axis`); ``design``: ``"grid"`` or
    ``"random"`` (``samples`` points drawn with ``design_seed``); ``seeds``: runs per point and robot count, seeds
    ``first_seed`` … ``first_seed + seeds − 1``; ``robots``: robot counts (``(None,)``: the script's own; a script
    declaring a ``robots`` parameter gets the count as its value too); ``config``: the runs' configuration (duration,
    sandbox, disturbances, jail; its ``runs``/``seed`` are set per run); ``barrier``: runs with the barrier on (as
    the arena runs them), else raw; ``capsules``: record every run and write its capsule, ``DIR/capsules/KEY.zip``
    (``swarmdeck run KEY.zip`` reproduces it: :mod:`~swarmdeck.console.sweep.capsules`).
    """

    bundle: ScriptBundle
    axes: tuple[Axis, ...] = ()
    seeds: int = 1
    first_seed: int = 0
    robots: tuple[int | None, ...] = (None,)
    design: str = "grid"
    samples: int | None = None
    design_seed: int = 0
    config: VerificationConfig = field(default_factory=VerificationConfig)
    barrier: bool = True
    capsules: bool = False

    def __post_init__(self) -> None:
        if self.design not in ("grid", "random"):
            raise DesignError(f"--design must be grid or random, got {self.design!r}")
        if self.design == "random" and (self.samples is None or self.samples < 1):
            raise DesignError("--design random needs --samples M (M >= 1)")
        if isinstance(self.seeds, bool) or not isinstance(self.seeds, int) or self.seeds < 1:
            raise DesignError(f"--seeds must be >= 1, got {self.seeds!r}")
        if self.first_seed < 0:
            raise DesignError(f"--seed must be >= 0, got {self.first_seed}")


@dataclass(frozen=True)
class Plan:
    """The runs of a sweep, in the table's order (point, robot count, seed), and the declared parameters."""

    runs: tuple[SweepRun, ...]
    declared: dict[str, Value]
    axes: tuple[Axis, ...]


class SweepIncomplete(RuntimeError, SwarmdeckError):
    """The sweep stopped before every run finished (cancelled, interrupted, the executor failed): ``missing``
    names the runs not done; what finished is kept, and running the same sweep again continues."""

    def __init__(self, message: str, missing: Sequence[SweepRun], cpu_s: float = 0.0) -> None:
        super().__init__(message)
        self.missing = tuple(missing)
        self.cpu_s = float(cpu_s)  # CPU s of the runs that did finish (the portal charges it to the daily limit)


def describe(run: SweepRun) -> str:
    """``gain=0.5 spacing=0.3 robots=20 seed=3`` — a run as the researcher names it."""
    parts = [f"{k}={v}" for k, v in run.params if k != "robots"]
    if run.robots is not None:
        parts.append(f"robots={run.robots}")
    return " ".join([*parts, f"seed={run.seed}"])


def declared_params(bundle: ScriptBundle) -> dict[str, Value]:
    """The parameters the entry script declares (``swarmdeck.devices.params``), read from its source without
    running it; DesignError for a script that does not compile or declares them in a form a sweep cannot read."""
    problem = compile_check(bundle)
    if problem is not None:
        raise DesignError(problem)
    try:
        return declared_in_source(bundle.source.decode("utf-8", "replace"), bundle.entry) or {}
    except ParamError as exc:
        raise DesignError(str(exc)) from None


def plan(spec: SweepSpec) -> Plan:
    """The sweep's runs; DesignError for an undeclared parameter, a reserved name, a design too large."""
    declared = declared_params(spec.bundle)
    clash = sorted(RESERVED & set(declared))
    if clash:
        raise DesignError(f"{spec.bundle.entry} declares parameter{'s' if len(clash) > 1 else ''} {', '.join(clash)}: "
                          f"a column of the sweep's table has that name; rename it")
    axes = check_axes(spec.axes, declared, spec.bundle.entry)
    check_size(axes, spec.design, spec.samples, len(spec.robots), spec.seeds)
    points = (grid_points(axes) if spec.design == "grid"
              else random_points(axes, declared, int(spec.samples or 0), spec.design_seed))
    version = swarmdeck_version()
    mode = "wrapped" if spec.barrier else "raw"
    runs = []
    for p, point in enumerate(points):
        for robots in spec.robots:
            values = dict(point)
            if robots is not None and "robots" in declared:
                values["robots"] = robots
            for s in range(spec.first_seed, spec.first_seed + spec.seeds):
                cfg = _run_config(spec.config, robots, s)
                key = run_key(dict(spec.bundle.files), entry=spec.bundle.entry, params=values, seed=s,
                              config={"run": cfg.to_dict(), "robots": robots, "mode": mode}, swarmdeck=version)
                params = tuple(values.items()) if declared else None
                runs.append(SweepRun(key, p, tuple(values.items()), robots, s,
                                     RunTask(spec.bundle, cfg, 0, mode, params=params)))
    return Plan(tuple(runs), declared, axes)


def _run_config(base: VerificationConfig, robots: int | None, seed: int) -> VerificationConfig:
    from dataclasses import replace

    return replace(base, n_robots=robots, runs=1, seed=seed, paced_runs=0, initial_poses=None,
                   declared_by="--robots")


def _write_atomic(path: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


class RunCache:
    """``DIR/runs/KEY.json``: the finished runs' rows. A file that cannot be read (cut, edited) is run again."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        folder.mkdir(parents=True, exist_ok=True)

    def get(self, key: str) -> dict[str, Any] | None:
        try:
            row = json.loads((self.folder / f"{key}.json").read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        return row if isinstance(row, dict) and row.get("key") == key else None

    def put(self, row: dict[str, Any]) -> None:
        _write_atomic(self.folder / f"{row['key']}.json", json.dumps(row, sort_keys=True, allow_nan=False))


@dataclass(frozen=True)
class SweepProgress:
    """After each finished run: how many are done of the total (cached runs count as done from the start)."""

    done: int
    total: int
    run: SweepRun
    row: dict[str, Any]


@dataclass
class SweepResult:
    """The rows in the plan's order (``cpu_s`` aside), how many ran now and how many came from the cache."""

    plan: Plan
    rows: list[dict[str, Any]]
    ran: int
    cached: int
    executor: str
    cpu_s: list[float] = field(default_factory=list)

    @property
    def failed(self) -> int:
        return sum(1 for r in self.rows if r["status"] != "ok")


def _table_row(row: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in row.items() if k != "cpu_s"}


def run_sweep(spec: SweepSpec, out: str | Path, executor: Any = None, *,
              on_progress: Callable[[SweepProgress], None] | None = None, cancel: Any = None) -> SweepResult:
    """Run the sweep into ``out`` (module docstring) on ``executor`` (default: the local pool) and write its outputs.

    ``cancel``: anything with ``is_set()``; once set, runs under way stop and :class:`SweepIncomplete` is raised
    naming the runs not done (as when the executor fails, e.g. a Ray cluster gone). DesignError for a sweep that
    cannot run; ConfinementUnavailable where the sandbox cannot confine code (and the config is not trusted).
    """
    from swarmdeck.console.sandbox.cancel_file import cancel_file
    from swarmdeck.console.sandbox.confinement import ConfinementUnavailable, probe
    from swarmdeck.console.sandbox.executors import LocalPoolExecutor
    from swarmdeck.console.sweep.outputs import write_outputs

    the_plan = plan(spec)
    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    cache = RunCache(folder / "runs")
    _write_atomic(folder / "sweep.json", json.dumps(_spec_json(spec, the_plan), indent=2, sort_keys=True))
    capsule_dir = folder / CAPSULES_DIR

    def capsule_of(run: SweepRun) -> str | None:
        return str(capsule_dir / f"{run.key}.zip") if spec.capsules else None

    # with --capsules, a run whose capsule is missing runs again (its row alone reproduces nothing)
    rows: list[dict[str, Any] | None] = [
        cache.get(r.key) if not spec.capsules or (capsule_dir / f"{r.key}.zip").exists() else None
        for r in the_plan.runs]
    todo = [k for k, row in enumerate(rows) if row is None]
    cached = len(rows) - len(todo)
    executor = executor if executor is not None else LocalPoolExecutor()
    name = getattr(executor, "name", type(executor).__name__)
    cpu: list[float] = []
    if todo:
        reason = probe(spec.config.jail)
        if reason is not None and not spec.config.trusted:
            raise ConfinementUnavailable(f"cannot confine untrusted code on this machine: {reason}; "
                                         "pass --trusted to run it unconfined")
        from dataclasses import replace

        finished = [cached]
        failure: BaseException | None = None
        with cancel_file(cancel, "swarmdeck-sweep-cancel") as (cancel_path, cancelled):
            tasks = [replace(the_plan.runs[k], task=replace(the_plan.runs[k].task, cancel_path=cancel_path),
                             capsule=capsule_of(the_plan.runs[k])) for k in todo]

            def done(i: int, row: dict[str, Any], _count: int) -> None:
                cpu.append(float(row.get("cpu_s") or 0.0))  # a run stopped half-way used CPU too (the portal charges it)
                if row.get("ended_by") == "cancelled":
                    return  # stopped half-way: nothing to keep
                kept = _table_row(row)
                if kept.get("ended_by") not in TRANSIENT:
                    cache.put(kept)
                rows[todo[i]] = kept
                finished[0] += 1
                if on_progress is not None:
                    on_progress(SweepProgress(finished[0], len(rows), tasks[i], kept))

            try:
                executor.run(tasks, done, cancelled, fn=run_point)
            except KeyboardInterrupt as exc:
                failure = exc
            except Exception as exc:  # noqa: BLE001 - the executor's infrastructure (a Ray cluster gone, a pool broken)
                failure = exc
        missing = [the_plan.runs[k] for k, row in enumerate(rows) if row is None]
        if missing or failure is not None:
            complete = [r for r in rows if r is not None]
            write_outputs(folder, the_plan, complete, spec)  # what is done, readable now
            why = ("it was cancelled" if cancel is not None and cancel.is_set() else
                   "it was interrupted" if isinstance(failure, KeyboardInterrupt) or failure is None else
                   f"the executor failed: {failure}")
            shown = ", ".join(describe(r) for r in missing[:10]) + (f" and {len(missing) - 10} more" if len(missing) > 10 else "")
            raise SweepIncomplete(f"the sweep stopped before {len(missing)} of {len(rows)} runs finished ({why}); "
                                  f"the {len(rows) - len(missing)} finished are kept in {folder}: run the same command "
                                  f"again to continue. Not done: {shown}", missing, sum(cpu)) from failure
    complete_rows = [r for r in rows if r is not None]
    write_outputs(folder, the_plan, complete_rows, spec)
    return SweepResult(the_plan, complete_rows, len(todo), cached, name, cpu)


def _spec_json(spec: SweepSpec, the_plan: Plan) -> dict[str, Any]:
    return {"schema": "swarmdeck.sweep/1", "script": spec.bundle.entry, "sha256": spec.bundle.sha256,
            "declared": the_plan.declared,
            "axes": [{"name": a.name, "kind": a.kind, "values": list(a.values)} for a in the_plan.axes],
            "design": spec.design, "samples": spec.samples, "design_seed": spec.design_seed,
            "seeds": spec.seeds, "first_seed": spec.first_seed, "robots": list(spec.robots),
            "barrier": spec.barrier, "runs": len(the_plan.runs), "swarmdeck": swarmdeck_version(),
            "config": _run_config(spec.config, None, 0).to_dict()}
