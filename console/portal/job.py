"""A portal job as the code sees it: one typed, frozen :class:`Job` made from its database row.

The job store (:mod:`.jobstore`) turns every ``jobs`` row into a :class:`Job`; the service, the verification
workers, the arena runner and the pages read its attributes. :meth:`Job.to_dict` is the job's JSON on the API
(the pydantic model :class:`~.models.JobOut` describes it in ``/openapi.json``). The bypass rule a job's columns
decide (:attr:`Job.bypass_pending`, :attr:`Job.bypass_allowed`) is here, once.

Pure Python (the thin CLI client imports :class:`ExportState`: no numpy, no FastAPI).
"""
from __future__ import annotations

import json
import sqlite3
from collections.abc import Mapping
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from swarmdeck.console.portal.states import JobState

#: the verification verdicts (:data:`swarmdeck.console.sandbox.verification.REJECTED`, ``BYPASS``; repeated here so
#: that this module stays free of numpy for the CLI client): a refusal, and the one that allows running without the
#: barrier
REJECTED_VERDICT = "rejected"
BYPASS_VERDICT = "accepted, may bypass the barrier"
#: the reason shown while a job waits for an operator's decision on its bypass
BYPASS_WAIT = "waiting for an operator to approve running without the barrier"


class ExportState(StrEnum):
    """Where a job's exports (CSV, HTML replay, video; :mod:`.exports`) are; the ``exports`` column (None: none)."""

    WRITING = "writing"
    READY = "ready"
    FAILED = "failed"


class BypassDecision(StrEnum):
    """An operator's decision on a job's barrier bypass; the ``bypass_decision`` column (None: none yet)."""

    APPROVED = "approved"
    REFUSED = "refused"


@dataclass(frozen=True)
class Job:
    """One job (a row of ``jobs`` with its owner's name and, when it is in the arena queue, its position).

    Times are UNIX seconds (None: not yet); ``duration`` is the declared run length, s; ``initial_poses`` one
    ``[x m, y m, θ rad]`` per robot or None (the arena's default start); ``position`` 0-based in the arena queue.
    """

    id: int
    user_id: int
    owner: str
    name: str
    state: JobState
    held_from: JobState | None
    kind: str  # "py" | "zip"
    script: str  # the uploaded file's display name
    entry: str  # what the sandbox runs: "script.py", or the .py inside the .zip
    robots: int
    duration: float
    initial_poses: tuple[tuple[float, ...], ...] | None
    request_no_barrier: bool
    barrier_forbidden: bool
    verdict: str | None
    safety_score: float | None
    bypass: bool | None
    reason: str | None
    bypass_decision: BypassDecision | None
    created: float
    updated: float
    started: float | None
    ended: float | None
    exports: ExportState | None
    results_deleted: float | None
    position: int | None = None
    # several arenas (issue 30): the arena the manifest asked for (None: any), physical/simulated/either, the arena
    # it was placed on when it started; the plan's estimate (:mod:`.scheduler`; None: not planned) — UNIX s
    arena: str | None = None
    needs: str = "either"
    placed: str | None = None
    eta_start: float | None = None
    eta_end: float | None = None
    eta_arena: str | None = None
    # a sweep job (issue 31): its request (console.portal.sweep_job.SweepRequest.to_dict); None: an arena job
    sweep: dict[str, Any] | None = None
    # the script's parameter values (manifest ``params``; None: its defaults) and the sweep job whose best point
    # this job runs (None: submitted directly) — migration 8
    params: dict[str, Any] | None = None
    origin: int | None = None

    @classmethod
    def from_row(cls, row: sqlite3.Row | Mapping[str, Any], position: int | None = None) -> Job:
        """A job from a ``jobs`` row joined with its owner's name (``owner``; :data:`.jobstore.JOB_SELECT`)."""
        poses = row["initial_poses"]
        return cls(
            id=int(row["id"]), user_id=int(row["user_id"]), owner=str(row["owner"]), name=str(row["name"]),
            state=JobState(row["state"]), held_from=None if row["held_from"] is None else JobState(row["held_from"]),
            kind=str(row["kind"]), script=str(row["script_name"]), entry=str(row["entry"]),
            robots=int(row["n_robots"]), duration=float(row["duration"]),
            initial_poses=None if poses is None else tuple(tuple(float(v) for v in p) for p in json.loads(poses)),
            request_no_barrier=bool(row["request_no_barrier"]), barrier_forbidden=bool(row["barrier_forbidden"]),
            verdict=row["verdict"], safety_score=row["safety_score"],
            bypass=None if row["bypass"] is None else bool(row["bypass"]), reason=row["reason"],
            bypass_decision=None if row["bypass_decision"] is None else BypassDecision(row["bypass_decision"]),
            created=float(row["created"]), updated=float(row["updated"]), started=row["started"], ended=row["ended"],
            exports=None if row["exports"] is None else ExportState(row["exports"]),
            results_deleted=row["results_deleted"], position=position, **_lab_columns(row))

    @property
    def bypass_pending(self) -> bool:
        """The job asks to run without the barrier, verification allowed it, and no operator decided yet."""
        return bypass_decided(self.verdict, self.request_no_barrier, self.barrier_forbidden, self.bypass_decision,
                              None)

    @property
    def bypass_allowed(self) -> bool:
        """Run the job without the barrier (with the guard): verification allowed it, the manifest asked, no
        operator forbade it and an operator approved this job's bypass."""
        return bypass_decided(self.verdict, self.request_no_barrier, self.barrier_forbidden, self.bypass_decision,
                              BypassDecision.APPROVED)

    def to_dict(self) -> dict[str, Any]:
        """The job's JSON on the API (:class:`~.models.JobOut`): every attribute but ``user_id``, plus
        ``bypass_pending``; states as their strings."""
        return {
            "id": self.id, "name": self.name, "owner": self.owner, "state": self.state,
            "held_from": self.held_from, "kind": self.kind, "script": self.script, "entry": self.entry,
            "robots": self.robots, "duration": self.duration,
            "initial_poses": None if self.initial_poses is None else [list(p) for p in self.initial_poses],
            "request_no_barrier": self.request_no_barrier, "barrier_forbidden": self.barrier_forbidden,
            "verdict": self.verdict, "safety_score": self.safety_score, "bypass": self.bypass, "reason": self.reason,
            "bypass_decision": self.bypass_decision, "bypass_pending": self.bypass_pending,
            "position": self.position, "created": self.created, "updated": self.updated, "started": self.started,
            "ended": self.ended, "exports": self.exports, "results_deleted": self.results_deleted,
            "arena": self.arena, "needs": self.needs, "placed": self.placed, "eta_start": self.eta_start,
            "eta_end": self.eta_end, "eta_arena": self.eta_arena, "sweep": self.sweep,
            "params": self.params, "origin": self.origin,
        }


def _lab_columns(row: sqlite3.Row | Mapping[str, Any]) -> dict[str, Any]:
    """The columns of migration 6 (an arena asked for, needs, where it ran), when the row has them."""
    keys = row.keys()
    found: dict[str, Any] = {k: row[k] for k in ("arena", "needs", "placed") if k in keys and row[k] is not None}
    if "sweep" in keys and row["sweep"] is not None:  # migration 7: a sweep job's request
        found["sweep"] = json.loads(row["sweep"])
    if "params" in keys and row["params"] is not None:  # migration 8: the script's parameters, the promoting sweep
        found["params"] = json.loads(row["params"])
    if "origin" in keys and row["origin"] is not None:
        found["origin"] = int(row["origin"])
    return found


def bypass_decided(verdict: str | None, request_no_barrier: bool, barrier_forbidden: bool,
                   decision: str | None, wanted: BypassDecision | None) -> bool:
    """The bypass rule: verification said "may bypass", the manifest asked (``no_barrier``), no operator forbade
    it, and the operator's decision is ``wanted`` (None: none yet — the job waits for it; ``approved``: it runs
    without the barrier)."""
    return (verdict == BYPASS_VERDICT and bool(request_no_barrier) and not barrier_forbidden
            and decision == wanted)


def valid_id(job_id: object) -> bool:
    """Whether ``job_id`` can be a job's id: an integer, 1 <= id < 2**63 (what SQLite's INTEGER holds)."""
    return isinstance(job_id, int) and not isinstance(job_id, bool) and 1 <= job_id < 2 ** 63
