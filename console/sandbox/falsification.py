"""The falsification stage of verification: search the set-up tolerance for the run closest to a contact.

After a script's raw and wrapped runs, :func:`falsify_script` spends ``VerificationConfig.falsify_budget``
more raw runs (no barrier, the same sandbox, the same executor: local pool or Ray) on candidates the
cross-entropy method (:func:`~swarmdeck.console.sandbox.falsify.cross_entropy`) picks from the set-up
tolerance (2 cm, 5°) and a constant tracking offset within the configured noise
(:class:`~swarmdeck.console.sandbox.falsify.SearchSpace`). Its objective is the run's minimum clearance —
between two robots (centre distance − diameter) or a robot and an obstacle segment (distance − radius) — from
the raw, unfiltered simulation (0: a contact; the search stops there). The worst case is run once more with
its recording kept (``<script>-worst-case.mcap``: ``swarmdeck play`` it) — the run is a pure function of its
task, so the replay is that run.

Searched runs are chosen, not drawn at random: they never enter the Clopper–Pearson bound (REFERENCE.md §17),
which counts the independent raw runs only. A contact found refuses the bypass, saying where and when.
Deterministic given the configuration's seed: candidates, runs and report.
"""
from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.sandbox.bundle import ScriptBundle
from swarmdeck.console.sandbox.falsify import SearchSpace, cross_entropy
from swarmdeck.console.sandbox.verification import RunTask, VerificationConfig, run_task
from swarmdeck.core.errors import SwarmdeckError

METHOD = "cross-entropy"
#: the report's note on the bound
NOT_IN_BOUND = "searched runs are chosen, not random: the bound counts the raw runs only"

#: ``run(tasks) -> results`` in task order (None: a run that was cancelled), e.g. an executor's ``run``
RunBatch = Callable[[Sequence[RunTask]], list[dict[str, Any] | None]]


class SearchCancelled(SwarmdeckError):
    """A searched run was cancelled: the verification stops."""


def _mm(clearance: float) -> str:
    return f"{clearance * 1000:.0f} mm"


def _where(closest: dict[str, Any]) -> str:
    t = closest.get("contact_time", closest["time"])
    if closest["kind"] == "robots":
        i, j = closest["robots"]
        return f"robots {i} and {j} at t = {t:.1f} s"
    if closest["kind"] == "obstacle":
        return f"robot {closest['robot']} and obstacle segment {closest['segment']} at t = {t:.1f} s"
    return "nothing came near"


def statement(entry: dict[str, Any]) -> str:
    """One line for the report: "worst case found: 3 mm, replay attached (robots 0 and 1 at t = 1.7 s)"."""
    worst = entry.get("worst_case")
    if worst is None:
        return f"falsification: {entry.get('skipped', 'no run measured a clearance')}"
    c = worst["closest"]
    found = "a contact" if c["clearance"] == 0.0 else _mm(c["clearance"])
    replay = ", replay attached" if entry.get("recording") else ""
    return f"worst case found: {found}{replay} ({worst['where']})"


def skipped(reason: str, budget: int) -> dict[str, Any]:
    """The report entry of a script the falsifier did not search (``reason``)."""
    return {"method": METHOD, "budget": budget, "runs": 0, "skipped": reason, "worst_case": None,
            "found_contact": False, "recording": None, "not_in_bound": NOT_IN_BOUND,
            "statement": f"falsification skipped: {reason}"}


def falsify_script(bundle: ScriptBundle, config: VerificationConfig, n_robots: int, run_batch: RunBatch,
                   cancel_path: str | None = None, record_dir: str | Path | None = None,
                   record_name: str | None = None,
                   params: tuple[tuple[str, Any], ...] | None = None) -> dict[str, Any]:
    """Search ``config.falsify_budget`` raw runs of ``bundle`` (``n_robots`` robots) for the closest approach
    (``params``: the script's parameter values in every searched run, :attr:`RunTask.params`).

    ``run_batch`` runs one generation's tasks (in parallel on the executor); :class:`SearchCancelled` when one
    was cancelled. With ``record_dir``, the worst case is run once more in this process and recorded to
    ``record_dir/record_name`` (default ``<entry stem>-worst-case.mcap``). Returns the report entry
    (``falsification`` beside ``contact_bound``): budget, runs spent, the worst case (its clearance m, what
    came close and when, its probe, start poses), every searched run's clearance and the statement.
    """
    budget = config.falsify_budget
    space = SearchSpace.within_noise(n_robots, config.disturbances.pose_noise_xy, config.disturbances.pose_noise_theta)
    runs: list[dict[str, Any]] = []

    def objective(batch: NDArray[np.float64]) -> NDArray[np.float64]:
        first = len(runs)
        tasks = [RunTask(bundle, config, first + k, "falsify", cancel_path, space.decode(z), params=params)
                 for k, z in enumerate(batch)]
        results = run_batch(tasks)
        if any(r is None or r["ended_by"] == "cancelled" for r in results):
            raise SearchCancelled("a searched run was cancelled")
        runs.extend(r for r in results if r is not None)
        return np.array([np.inf if r is None or r.get("closest", {}).get("clearance") is None
                         else float(r["closest"]["clearance"]) for r in results])

    found = cross_entropy(objective, space.dim, budget, config.seed)
    best = found.best
    if not np.isfinite(found.values[best]):
        return {**skipped("no searched run measured a clearance (see the raw runs' errors)", budget), "runs": len(runs)}
    worst_run = runs[best]
    probe = space.decode(found.candidates[best])
    worst = {"run": best, "closest": worst_run["closest"], "where": _where(worst_run["closest"]), "probe": probe.to_dict(),
             "start_poses": worst_run["start_poses"], "error": worst_run["error"],
             "contacts": worst_run["contacts"]}
    entry: dict[str, Any] = {
        "method": METHOD, "budget": budget, "runs": len(runs), "generations": found.generations,
        "found_contact": worst_run["closest"]["clearance"] == 0.0, "worst_case": worst, "recording": None,
        "clearances": [None if not np.isfinite(v) else round(float(v), 6) for v in found.values],
        "not_in_bound": NOT_IN_BOUND,
    }
    if record_dir is not None:
        name = record_name or f"{Path(bundle.entry).stem}-worst-case.mcap"
        path = Path(record_dir) / name
        replay = run_task(RunTask(bundle, config, best, "falsify", cancel_path, probe, record=str(path),
                                  params=params))
        if replay["ended_by"] == "cancelled":
            raise SearchCancelled("the worst case's replay was cancelled")
        recorded = bool(replay.get("recorded")) and path.exists()
        entry["recording"] = name if recorded else None
        entry["replay_matches"] = replay.get("closest") == worst_run["closest"]
    entry["statement"] = statement(entry)
    return entry
