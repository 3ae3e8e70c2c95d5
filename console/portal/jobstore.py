"""The portal's jobs in the database: every SQL statement on ``jobs``, ``verification_usage`` and the arena's
settings, in one place; rows come out as typed :class:`~.job.Job`.

The service (:mod:`.service`) holds the rules and calls these. Reads run on the thread's connection (autocommit:
they see the newest committed state); changes take the caller's transaction ``tx``
(:meth:`~.db.Database.transaction`), so a rule that changes several rows, files or the audit log commits them as
one. State changes go through :meth:`JobStore.transition` (the conditional ``UPDATE`` of :mod:`.db`'s state
machine). The schema and its migrations stay in :mod:`.db`; accounts, tokens and sessions in :mod:`.accounts`.
"""
from __future__ import annotations

import builtins
import json
import sqlite3
import time
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from typing import Any, Protocol

from swarmdeck.console.portal.db import Database
from swarmdeck.console.portal.job import BYPASS_VERDICT, BYPASS_WAIT, ExportState, Job, valid_id
from swarmdeck.console.portal.states import ACTIVE, FINAL, JobState

#: a job row with its owner's name (``owner``)
JOB_SELECT = "SELECT j.*, u.name AS owner FROM jobs j JOIN users u ON u.id = j.user_id"
#: SQL: the job waits for an operator's decision on its bypass (columns of ``jobs``; :attr:`.Job.bypass_pending`)
PENDING_SQL = (f"(COALESCE(verdict, '') = '{BYPASS_VERDICT}' AND request_no_barrier = 1 "
               "AND barrier_forbidden = 0 AND bypass_decision IS NULL)")
QUEUE_ORDER = "ORDER BY priority, id"
#: jobs waiting for an arena (or before it): where fair share places a new job
WAITING: tuple[JobState, ...] = (JobState.AWAITING_VERIFICATION, JobState.VERIFYING, JobState.AWAITING_APPROVAL,
                                 JobState.IN_ARENA_QUEUE, JobState.HELD)
#: jobs on their way to the arena queue (planned after it, for their estimated times)
PRE_QUEUE: tuple[JobState, ...] = (JobState.AWAITING_VERIFICATION, JobState.VERIFYING, JobState.AWAITING_APPROVAL)
Tx = sqlite3.Connection


#: SQL: the job was placed on arena ? (``placed`` is the arena, or ``ARENA/REGION`` on a floor divided into regions;
#: NULL counts on the default arena). Parameters: default, arena, arena, arena.
_ON_ARENA = "COALESCE({p}placed, ?) = ? OR substr({p}placed, 1, length(?) + 1) = ? || '/'"

def _marks(values: Sequence[object]) -> str:
    return ", ".join("?" * len(values))


class JobStore:
    """The jobs' rows (module docstring) of one :class:`~.db.Database`. Thread-safe as the database is."""

    def __init__(self, db: Database) -> None:
        self.db = db

    @contextmanager
    def transaction(self) -> Iterator[Tx]:
        """One whole change (:meth:`.Database.transaction`)."""
        with self.db.transaction() as tx:
            yield tx

    # ------------------------------------------------------------------ reading jobs
    def get(self, job_id: int, tx: Tx | None = None) -> Job | None:
        """The job ``job_id`` (with its queue position), None when there is none or the id cannot be one
        (:func:`.job.valid_id`: such an id is "no job", never an SQL error)."""
        if not valid_id(job_id):
            return None
        conn = tx if tx is not None else self.db.connection()
        row = conn.execute(f"{JOB_SELECT} WHERE j.id = ?", (int(job_id),)).fetchone()
        if row is None:
            return None
        return Job.from_row(row, self._positions(conn).get(int(row["id"])) if row["state"] == JobState.IN_ARENA_QUEUE
                            else None)

    def state(self, job_id: int) -> JobState | None:
        """The job's state (None: no such job)."""
        if not valid_id(job_id):
            return None
        row = self.db.query_one("SELECT state FROM jobs WHERE id = ?", (int(job_id),))
        return None if row is None else JobState(row["state"])

    def list(self, user_id: int | None = None) -> list[Job]:
        """Every job (``user_id``: that user's), newest first, with queue positions."""
        positions = self._positions(self.db.connection())
        if user_id is None:
            rows = self.db.query(f"{JOB_SELECT} ORDER BY j.id DESC")
        else:
            rows = self.db.query(f"{JOB_SELECT} WHERE j.user_id = ? ORDER BY j.id DESC", (int(user_id),))
        return [Job.from_row(r, positions.get(int(r["id"]))) for r in rows]

    def queue(self) -> builtins.list[Job]:
        """The arena queue, in the order jobs will run."""
        rows = self.db.query(f"{JOB_SELECT} WHERE j.state = ? ORDER BY j.priority, j.id", (JobState.IN_ARENA_QUEUE,))
        return [Job.from_row(r, k) for k, r in enumerate(rows)]

    def first_in_queue(self, tx: Tx | None = None) -> Job | None:
        """The next job for the arena (None: the queue is empty)."""
        conn = tx if tx is not None else self.db.connection()
        row = conn.execute(f"{JOB_SELECT} WHERE j.state = ? ORDER BY j.priority, j.id LIMIT 1",
                           (JobState.IN_ARENA_QUEUE,)).fetchone()
        return None if row is None else Job.from_row(row, 0)

    def on_arena(self) -> Job | None:
        """The job on the arena (setting up or running), None when it is idle."""
        row = self.db.query_one(f"{JOB_SELECT} WHERE j.state IN ({_marks(ACTIVE)}) ORDER BY j.id LIMIT 1", ACTIVE)
        return None if row is None else Job.from_row(row)

    def queue_ids(self, tx: Tx) -> builtins.list[int]:
        """The ids of the arena queue, in the order jobs will run."""
        return [int(r["id"]) for r in tx.execute(f"SELECT id FROM jobs WHERE state = ? {QUEUE_ORDER}",
                                                 (JobState.IN_ARENA_QUEUE,)).fetchall()]

    def _positions(self, conn: Tx) -> dict[int, int]:
        rows = conn.execute(f"SELECT id FROM jobs WHERE state = ? {QUEUE_ORDER}", (JobState.IN_ARENA_QUEUE,))
        return {int(r["id"]): k for k, r in enumerate(rows.fetchall())}

    def ids_in(self, tx: Tx, states: Sequence[JobState]) -> builtins.list[int]:
        """The ids of the jobs in ``states``, oldest first."""
        return [int(r["id"]) for r in tx.execute(f"SELECT id FROM jobs WHERE state IN ({_marks(states)}) ORDER BY id",
                                                 tuple(states)).fetchall()]

    def bypass_pending(self, tx: Tx, job_id: int) -> bool:
        """:attr:`.Job.bypass_pending` of the row as ``tx`` sees it."""
        return bool(tx.execute(f"SELECT {PENDING_SQL} AS p FROM jobs WHERE id = ?", (int(job_id),)).fetchone()["p"])

    # ------------------------------------------------------------------ changing jobs
    def insert(self, tx: Tx, *, user_id: int, name: str, kind: str, script: str, entry: str, robots: int,
               duration: float, initial_poses: Sequence[Sequence[float]] | None, no_barrier: bool, now: float,
               arena: str | None = None, needs: str = "either", params: Mapping[str, Any] | None = None,
               origin: int | None = None) -> int:
        """A new job, ``awaiting verification``, at its fair-share place (:meth:`fair_priority`); its id.
        ``params``: the script's parameter values (None: its defaults); ``origin``: the sweep job it was promoted
        from."""
        cur = tx.execute(
            "INSERT INTO jobs (user_id, name, state, kind, script_name, entry, n_robots, duration, initial_poses, "
            "request_no_barrier, priority, created, updated, arena, needs, params, origin) "
            "VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
            (user_id, name, JobState.AWAITING_VERIFICATION, kind, script, entry, robots, duration,
             None if initial_poses is None else json.dumps(initial_poses), int(no_barrier),
             self.fair_priority(tx, user_id), now, now, arena, needs,
             None if params is None else json.dumps(dict(params), sort_keys=True),
             None if origin is None else int(origin)))
        return int(cur.lastrowid or 0)

    def set_sweep(self, tx: Tx, job_id: int, request: dict[str, Any]) -> None:
        """Make the new job ``job_id`` a sweep job with ``request`` (:class:`.sweep_job.SweepRequest` as a dict)."""
        tx.execute("UPDATE jobs SET sweep = ? WHERE id = ?", (json.dumps(request, sort_keys=True), int(job_id)))

    def fair_priority(self, tx: Tx, user_id: int) -> float:
        """The priority of a new job of ``user_id``: fair share between researchers (issue 30).

        Start-time fair queueing over job counts: the head of the waiting jobs (the lowest priority of any job
        not yet on an arena; with none, after every job so far), or one after the owner's own last waiting job,
        whichever is later. A researcher who submits a batch of ten gets ten consecutive places; another's
        single job submitted afterwards goes in at the head, level with the batch's first (the id breaks the
        tie), so batches interleave one job each instead of one researcher's batch starving the others. With one
        researcher this is first come, first served, as before."""
        head = tx.execute(f"SELECT MIN(priority) FROM jobs WHERE state IN ({_marks(WAITING)})", WAITING).fetchone()[0]
        if head is None:
            head = tx.execute("SELECT COALESCE(MAX(priority), 0) + 1 FROM jobs").fetchone()[0]
        own = tx.execute(f"SELECT MAX(priority) FROM jobs WHERE user_id = ? AND state IN ({_marks(WAITING)})",
                         (int(user_id), *WAITING)).fetchone()[0]
        return float(head if own is None else max(head, own + 1))

    # ------------------------------------------------------------------ several arenas (issue 30)
    def waiting_in_order(self) -> builtins.list[Job]:
        """Every job not yet on an arena and not held, in the order the plan takes them: the arena queue first,
        then the jobs still in verification or awaiting approval (by priority). Sweep jobs never go to an arena:
        not here."""
        rows = self.db.query(f"{JOB_SELECT} WHERE j.state IN ({_marks(PRE_QUEUE)}) AND j.sweep IS NULL "
                             "ORDER BY j.priority, j.id", PRE_QUEUE)
        return [*self.queue(), *(Job.from_row(r) for r in rows)]

    def active_on(self, arena: str, default: str, tx: Tx | None = None) -> builtins.list[Job]:
        """The jobs on ``arena`` now (setting up or running); jobs placed before there were several arenas count
        on ``default``."""
        conn = tx if tx is not None else self.db.connection()
        rows = conn.execute(f"{JOB_SELECT} WHERE j.state IN ({_marks(ACTIVE)}) AND ({_ON_ARENA.format(p='j.')}) "
                            "ORDER BY j.id", (*ACTIVE, default, arena, arena, arena)).fetchall()
        return [Job.from_row(r) for r in rows]

    def recent_runs(self, arena: str, default: str, limit: int) -> builtins.list[tuple[float, float, float]]:
        """(started, ended, declared duration) of the last ``limit`` jobs ``done`` on ``arena``, oldest first."""
        rows = self.db.query(f"SELECT started, ended, duration FROM jobs WHERE state = ? AND ({_ON_ARENA.format(p='')}) "
                             "AND started IS NOT NULL AND ended IS NOT NULL ORDER BY ended DESC LIMIT ?",
                             (JobState.DONE, default, arena, arena, arena, int(limit)))
        return [(float(r["started"]), float(r["ended"]), float(r["duration"])) for r in reversed(rows)]

    def set_holder(self, tx: Tx, job_id: int, holder: str | None) -> None:
        """Record which remote runner lease holds the job (None: none, or an in-process runner)."""
        tx.execute("UPDATE jobs SET holder = ? WHERE id = ?", (holder, int(job_id)))

    def held_by(self, holder: str, tx: Tx | None = None) -> builtins.list[int]:
        """The ids of the active jobs a remote runner lease holds."""
        conn = tx if tx is not None else self.db.connection()
        return [int(r["id"]) for r in conn.execute(f"SELECT id FROM jobs WHERE holder = ? AND state IN "
                                                   f"({_marks(ACTIVE)})", (holder, *ACTIVE)).fetchall()]

    def holder_of(self, job_id: int) -> str | None:
        row = self.db.query_one("SELECT holder FROM jobs WHERE id = ?", (int(job_id),))
        return None if row is None else row["holder"]

    def arena_stopped_named(self, arena: str) -> bool:
        """One arena's emergency-stop latch (the whole portal's: :meth:`arena_stopped`)."""
        return self.db.setting(f"arena_stopped:{arena}", "0") == "1"

    def set_arena_stopped_named(self, tx: Tx, arena: str, stopped: bool) -> None:
        self.db.set_setting(tx, f"arena_stopped:{arena}", "1" if stopped else "0")

    def transition(self, tx: Tx, job_id: int, target: JobState, *, sources: tuple[JobState, ...] | None = None,
                   **columns: Any) -> None:
        """The state machine's conditional move (:meth:`.Database.transition`; :class:`.db.TransitionConflict`)."""
        self.db.transition(tx, int(job_id), target, sources=sources, **columns)

    def state_in(self, tx: Tx, job_id: int) -> JobState | None:
        """The job's state as ``tx`` sees it (None: no such job)."""
        row = tx.execute("SELECT state FROM jobs WHERE id = ?", (int(job_id),)).fetchone()
        return None if row is None else JobState(row["state"])

    def set_barrier_forbidden(self, tx: Tx, job_id: int, forbid: bool) -> bool:
        """Forbid (or allow) the job's bypass unless it is on the arena or has ended; whether it changed."""
        blocked = (*ACTIVE, *FINAL)
        cur = tx.execute(f"UPDATE jobs SET barrier_forbidden = ?, updated = ? WHERE id = ? AND state NOT IN "
                         f"({_marks(blocked)})", (int(forbid), time.time(), int(job_id), *blocked))
        return cur.rowcount == 1

    def requeue_bypass_wait(self, tx: Tx, job_id: int) -> None:
        """A job awaiting the decision on its (now forbidden) bypass goes to the arena queue, with the barrier."""
        tx.execute("UPDATE jobs SET state = ?, reason = NULL WHERE id = ? AND state = ? AND reason = ?",
                   (JobState.IN_ARENA_QUEUE, int(job_id), JobState.AWAITING_APPROVAL, BYPASS_WAIT))

    def back_to_bypass_wait(self, tx: Tx, job_id: int) -> None:
        """A queued job whose bypass is allowed again waits for an operator's decision on it."""
        tx.execute(f"UPDATE jobs SET state = ?, reason = ? WHERE id = ? AND state = ? AND {PENDING_SQL}",
                   (JobState.AWAITING_APPROVAL, BYPASS_WAIT, int(job_id), JobState.IN_ARENA_QUEUE))

    def release_approved(self, tx: Tx) -> None:
        """Every job awaiting approval that is not waiting for a bypass decision goes to the arena queue."""
        tx.execute(f"UPDATE jobs SET state = ?, updated = ? WHERE state = ? AND NOT {PENDING_SQL}",
                   (JobState.IN_ARENA_QUEUE, time.time(), JobState.AWAITING_APPROVAL))

    def decide_bypass_in_place(self, tx: Tx, job_id: int, decision: str, forbidden: bool) -> bool:
        """Record an operator's bypass decision on a job that stays ``awaiting approval``; whether it was."""
        cur = tx.execute("UPDATE jobs SET bypass_decision = ?, barrier_forbidden = ?, reason = NULL, updated = ? "
                         "WHERE id = ? AND state = ?",
                         (decision, int(forbidden), time.time(), int(job_id), JobState.AWAITING_APPROVAL))
        return cur.rowcount == 1

    def set_reason(self, tx: Tx, job_id: int, reason: str | None) -> None:
        """Set what the job's page says it waits for or why it ended (None: nothing)."""
        tx.execute("UPDATE jobs SET reason = ? WHERE id = ?", (reason, int(job_id)))

    def set_waiting_reason(self, job_id: int, reason: str) -> bool:
        """Say why a job in the arena queue does not start yet; whether that changed anything."""
        with self.transaction() as tx:
            cur = tx.execute("UPDATE jobs SET reason = ? WHERE id = ? AND state = ? AND COALESCE(reason, '') != ?",
                             (reason, int(job_id), JobState.IN_ARENA_QUEUE, reason))
        return cur.rowcount > 0

    def reorder_queue(self, tx: Tx, ids: builtins.list[int]) -> None:
        """Give the queued jobs ``ids`` priorities in that order (from the queue's lowest on)."""
        base = tx.execute("SELECT COALESCE(MIN(priority), 0) FROM jobs WHERE state = ?",
                          (JobState.IN_ARENA_QUEUE,)).fetchone()[0]
        for k, jid in enumerate(ids):
            tx.execute("UPDATE jobs SET priority = ? WHERE id = ?", (base + k * 1e-3, int(jid)))

    def next_for_verification(self, tx: Tx, last_owner: int) -> tuple[int, int] | None:
        """(job id, owner id) of the oldest job awaiting verification of the first owner after ``last_owner``
        (by user id, wrapping around); None when no job awaits verification."""
        row = tx.execute("SELECT id, user_id FROM jobs WHERE state = ? ORDER BY user_id <= ?, user_id, id LIMIT 1",
                         (JobState.AWAITING_VERIFICATION, int(last_owner))).fetchone()
        return None if row is None else (int(row["id"]), int(row["user_id"]))

    # ------------------------------------------------------------------ exports and retention
    def set_exports(self, job_id: int, state: ExportState) -> None:
        """Record where the job's exports are."""
        with self.transaction() as tx:
            tx.execute("UPDATE jobs SET exports = ? WHERE id = ?", (ExportState(state), int(job_id)))

    def exports_in(self, state: ExportState) -> builtins.list[int]:
        """The ids of the jobs whose exports are in ``state``, oldest first."""
        return [int(r["id"]) for r in self.db.query("SELECT id FROM jobs WHERE exports = ? ORDER BY id",
                                                    (ExportState(state),))]

    def ended_before(self, cutoff: float) -> builtins.list[int]:
        """Jobs that ended before ``cutoff`` (UNIX s), still have their results and no exports being written."""
        rows = self.db.query(f"SELECT id FROM jobs WHERE state IN ({_marks(FINAL)}) AND ended IS NOT NULL AND "
                             "ended < ? AND results_deleted IS NULL AND COALESCE(exports, '') != ? ORDER BY id",
                             (*FINAL, cutoff, ExportState.WRITING))
        return [int(r["id"]) for r in rows]

    def mark_results_deleted(self, job_id: int, when: float) -> None:
        """Record that the retention sweep deleted the job's folder at ``when`` (UNIX s); the row stays."""
        with self.transaction() as tx:
            tx.execute("UPDATE jobs SET results_deleted = ? WHERE id = ?", (when, int(job_id)))

    # ------------------------------------------------------------------ what a researcher uses (quotas)
    def kept_job_ids(self, user_id: int) -> builtins.list[int]:
        """The user's jobs whose results were not deleted."""
        return [int(r["id"]) for r in self.db.query("SELECT id FROM jobs WHERE user_id = ? AND results_deleted IS NULL",
                                                    (int(user_id),))]

    def unfinished_count(self, user_id: int, tx: Tx | None = None) -> int:
        """How many of the user's jobs have not ended."""
        conn = tx if tx is not None else self.db.connection()
        return int(conn.execute(f"SELECT COUNT(*) FROM jobs WHERE user_id = ? AND state NOT IN ({_marks(FINAL)})",
                                (int(user_id), *FINAL)).fetchone()[0])

    def verification_cpu(self, user_id: int, since: float, tx: Tx | None = None) -> builtins.list[tuple[float, float]]:
        """(when, CPU s) of the verification of each of the user's jobs recorded after ``since``, oldest first."""
        conn = tx if tx is not None else self.db.connection()
        rows = conn.execute("SELECT t, cpu_s FROM verification_usage WHERE user_id = ? AND t > ? ORDER BY t",
                            (int(user_id), float(since))).fetchall()
        return [(float(r["t"]), float(r["cpu_s"])) for r in rows]

    def record_verification_cpu(self, job_id: int, cpu_s: float) -> None:
        """Charge ``cpu_s`` CPU seconds of the job's verification to its owner (replacing an earlier charge)."""
        with self.transaction() as tx:
            tx.execute("INSERT OR REPLACE INTO verification_usage (job_id, user_id, t, cpu_s) "
                       "SELECT id, user_id, ?, ? FROM jobs WHERE id = ?", (time.time(), float(cpu_s), int(job_id)))

    # ------------------------------------------------------------------ the arena's switches (``settings``)
    def manual_approval(self) -> bool:
        """Whether an operator approves each verified job."""
        return self.db.setting("manual_approval", "0") == "1"

    def set_manual_approval(self, tx: Tx, on: bool) -> None:
        """Switch manual approval (the jobs it releases: :meth:`release_approved`)."""
        self.db.set_setting(tx, "manual_approval", "1" if on else "0")

    def arena_stopped(self) -> bool:
        """The emergency-stop latch (it survives a restart)."""
        return self.db.setting("arena_stopped", "0") == "1"

    def set_arena_stopped(self, tx: Tx, stopped: bool, attention: str | None = None) -> None:
        """Latch (or release) the arena; ``attention``: why it needs an operator ("" clears it, None keeps it)."""
        self.db.set_setting(tx, "arena_stopped", "1" if stopped else "0")
        if attention is not None:
            self.db.set_setting(tx, "arena_attention", attention)

    def attention(self) -> str | None:
        """Why the arena needs an operator (None: it does not)."""
        return self.db.setting("arena_attention", "") or None

    def last_verified_owner(self) -> int:
        """The user id whose job verification took last (0: none yet): the round-robin's turn."""
        return int(self.db.setting("verify_last_owner", "0"))

    def set_last_verified_owner(self, tx: Tx, user_id: int) -> None:
        """Record whose job verification took last."""
        self.db.set_setting(tx, "verify_last_owner", str(int(user_id)))


class JobStoreAPI(Protocol):
    """What the service (:mod:`.service`) asks of the jobs' store: every method of :class:`JobStore`, which is the
    SQLite one. Moving to another database (PostgreSQL: docs/lab.md) is a new class with these methods (and its
    ``transaction()`` yielding that database's transaction handle), not a change to the rules."""

    db: Database

    @contextmanager
    def transaction(self) -> Iterator[Tx]: ...

    def get(self, job_id: int, tx: Tx | None = None) -> Job | None: ...

    def state(self, job_id: int) -> JobState | None: ...

    def list(self, user_id: int | None = None) -> list[Job]: ...

    def queue(self) -> builtins.list[Job]: ...

    def first_in_queue(self, tx: Tx | None = None) -> Job | None: ...

    def on_arena(self) -> Job | None: ...

    def queue_ids(self, tx: Tx) -> builtins.list[int]: ...

    def ids_in(self, tx: Tx, states: Sequence[JobState]) -> builtins.list[int]: ...

    def bypass_pending(self, tx: Tx, job_id: int) -> bool: ...

    def insert(self, tx: Tx, *, user_id: int, name: str, kind: str, script: str, entry: str, robots: int,
               duration: float, initial_poses: Sequence[Sequence[float]] | None, no_barrier: bool, now: float,
               arena: str | None = None, needs: str = "either", params: Mapping[str, Any] | None = None,
               origin: int | None = None) -> int: ...

    def set_sweep(self, tx: Tx, job_id: int, request: dict[str, Any]) -> None: ...

    def fair_priority(self, tx: Tx, user_id: int) -> float: ...

    def waiting_in_order(self) -> builtins.list[Job]: ...

    def active_on(self, arena: str, default: str, tx: Tx | None = None) -> builtins.list[Job]: ...

    def recent_runs(self, arena: str, default: str, limit: int) -> builtins.list[tuple[float, float, float]]: ...

    def set_holder(self, tx: Tx, job_id: int, holder: str | None) -> None: ...

    def held_by(self, holder: str, tx: Tx | None = None) -> builtins.list[int]: ...

    def holder_of(self, job_id: int) -> str | None: ...

    def arena_stopped_named(self, arena: str) -> bool: ...

    def set_arena_stopped_named(self, tx: Tx, arena: str, stopped: bool) -> None: ...

    def transition(self, tx: Tx, job_id: int, target: JobState, *, sources: tuple[JobState, ...] | None = None,
                   **columns: Any) -> None: ...

    def state_in(self, tx: Tx, job_id: int) -> JobState | None: ...

    def set_barrier_forbidden(self, tx: Tx, job_id: int, forbid: bool) -> bool: ...

    def requeue_bypass_wait(self, tx: Tx, job_id: int) -> None: ...

    def back_to_bypass_wait(self, tx: Tx, job_id: int) -> None: ...

    def release_approved(self, tx: Tx) -> None: ...

    def decide_bypass_in_place(self, tx: Tx, job_id: int, decision: str, forbidden: bool) -> bool: ...

    def set_reason(self, tx: Tx, job_id: int, reason: str | None) -> None: ...

    def set_waiting_reason(self, job_id: int, reason: str) -> bool: ...

    def reorder_queue(self, tx: Tx, ids: builtins.list[int]) -> None: ...

    def next_for_verification(self, tx: Tx, last_owner: int) -> tuple[int, int] | None: ...

    def set_exports(self, job_id: int, state: ExportState) -> None: ...

    def exports_in(self, state: ExportState) -> builtins.list[int]: ...

    def ended_before(self, cutoff: float) -> builtins.list[int]: ...

    def mark_results_deleted(self, job_id: int, when: float) -> None: ...

    def kept_job_ids(self, user_id: int) -> builtins.list[int]: ...

    def unfinished_count(self, user_id: int, tx: Tx | None = None) -> int: ...

    def verification_cpu(self, user_id: int, since: float, tx: Tx | None = None) -> builtins.list[tuple[float, float]]: ...

    def record_verification_cpu(self, job_id: int, cpu_s: float) -> None: ...

    def manual_approval(self) -> bool: ...

    def set_manual_approval(self, tx: Tx, on: bool) -> None: ...

    def arena_stopped(self) -> bool: ...

    def set_arena_stopped(self, tx: Tx, stopped: bool, attention: str | None = None) -> None: ...

    def attention(self) -> str | None: ...

    def last_verified_owner(self) -> int: ...

    def set_last_verified_owner(self, tx: Tx, user_id: int) -> None: ...
