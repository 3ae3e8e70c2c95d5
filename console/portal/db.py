"""The portal's SQLite database: one file ``DIR/portal.sqlite3``, WAL, foreign keys, versioned schema.

* **Connections**: one per thread (:class:`Database` keeps them in a
  ``threading.local``), each with ``journal_mode=WAL``, ``foreign_keys=ON``,
  ``busy_timeout``, ``synchronous=NORMAL`` (WAL: a power cut loses at most the
  last transactions, never corrupts the file) and ``secure_delete`` (deleted rows
  are overwritten). The folder is ``0700`` and the files ``0600`` (:mod:`.files`). Autocommit mode: reads see the
  newest committed state; every change runs in :meth:`Database.transaction`
  (``BEGIN IMMEDIATE`` … ``COMMIT``, rolled back on any exception), so a killed
  server leaves each change either whole or absent.
* **Schema**: ``schema_version`` holds the version; :data:`MIGRATIONS` are
  applied in order on start, each in its own transaction together with the new
  version number. A database newer than this code is refused
  (:class:`SchemaError`).
* **Jobs' state machine** (:data:`TRANSITIONS`, the states :class:`~.states.JobState`):
  ``awaiting verification → verifying → rejected | awaiting approval → in arena queue →
  setting up → running → done | failed | cancelled | interrupted``, plus ``held`` (an
  operator's hold of a job awaiting verification or approval or in the arena queue;
  released back to the state it came from). A job whose verification said "may bypass
  the barrier" and whose manifest asked for it stays ``awaiting approval`` until an
  operator approves or refuses that bypass (``bypass_decision``, migration 3), whatever
  the manual-approval switch says. Migration 5 renamed the states ``queued``,
  ``approved`` and ``waiting`` of older files. Every
  transition is one conditional ``UPDATE … WHERE id = ? AND state IN (…)``
  (:meth:`Database.transition`): of two operators acting on one job at once,
  exactly one changes it, the other gets :class:`TransitionConflict` naming the
  state the job is in now.
"""
from __future__ import annotations

import sqlite3
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from swarmdeck.console.portal.files import private_dir, private_file
from swarmdeck.console.portal.states import ACTIVE, FINAL, RENAMED, JobState
from swarmdeck.core.errors import SwarmdeckError

__all__ = ["ACTIVE", "FINAL", "MIGRATIONS", "STATES", "TRANSITIONS", "Database", "JobState", "SchemaError",
           "TransitionConflict"]

FILENAME = "portal.sqlite3"

S = JobState
STATES: tuple[JobState, ...] = tuple(JobState)
#: state -> the states it may move to.
TRANSITIONS: dict[JobState, tuple[JobState, ...]] = {
    S.AWAITING_VERIFICATION: (S.VERIFYING, S.CANCELLED, S.HELD),
    # -> awaiting verification: a worker stopped mid-way (restart); -> done | failed: a sweep job (issue 31), which
    # runs in simulation on the verification executors and never enters the arena queue
    S.VERIFYING: (S.REJECTED, S.AWAITING_APPROVAL, S.AWAITING_VERIFICATION, S.CANCELLED, S.DONE, S.FAILED),
    S.AWAITING_APPROVAL: (S.IN_ARENA_QUEUE, S.CANCELLED, S.HELD),
    S.IN_ARENA_QUEUE: (S.SETTING_UP, S.CANCELLED, S.HELD),
    S.HELD: (S.AWAITING_VERIFICATION, S.AWAITING_APPROVAL, S.IN_ARENA_QUEUE, S.CANCELLED),
    S.SETTING_UP: (S.RUNNING, S.FAILED, S.CANCELLED, S.INTERRUPTED),
    S.RUNNING: (S.DONE, S.FAILED, S.CANCELLED, S.INTERRUPTED),
}
del S

MIGRATIONS: tuple[str, ...] = (
    # 1: accounts, sessions, sign-in attempts, jobs, audit log, settings
    """
    CREATE TABLE users (
        id INTEGER PRIMARY KEY,
        name TEXT NOT NULL UNIQUE,
        role TEXT NOT NULL CHECK (role IN ('researcher', 'operator')),
        disabled INTEGER NOT NULL DEFAULT 0,
        created REAL NOT NULL
    );
    CREATE TABLE tokens (
        id INTEGER PRIMARY KEY,
        user_id INTEGER NOT NULL REFERENCES users(id),
        hash TEXT NOT NULL UNIQUE,
        created REAL NOT NULL
    );
    CREATE TABLE sessions (
        hash TEXT PRIMARY KEY,
        user_id INTEGER NOT NULL REFERENCES users(id),
        csrf TEXT NOT NULL,
        created REAL NOT NULL,
        expires REAL NOT NULL
    );
    CREATE TABLE signin_failures (
        client TEXT NOT NULL,
        t REAL NOT NULL
    );
    CREATE INDEX signin_failures_client ON signin_failures (client, t);
    CREATE TABLE jobs (
        id INTEGER PRIMARY KEY,
        user_id INTEGER NOT NULL REFERENCES users(id),
        name TEXT NOT NULL,
        state TEXT NOT NULL,
        held_from TEXT,
        kind TEXT NOT NULL CHECK (kind IN ('py', 'zip')),
        script_name TEXT NOT NULL,
        entry TEXT NOT NULL,
        n_robots INTEGER NOT NULL,
        duration REAL NOT NULL,
        initial_poses TEXT,
        request_no_barrier INTEGER NOT NULL DEFAULT 0,
        barrier_forbidden INTEGER NOT NULL DEFAULT 0,
        verdict TEXT,
        safety_score REAL,
        bypass INTEGER,
        reason TEXT,
        priority REAL NOT NULL,
        created REAL NOT NULL,
        updated REAL NOT NULL,
        started REAL,
        ended REAL
    );
    CREATE INDEX jobs_state ON jobs (state, priority, id);
    CREATE INDEX jobs_user ON jobs (user_id, id);
    CREATE TABLE audit (
        id INTEGER PRIMARY KEY,
        t REAL NOT NULL,
        user_id INTEGER REFERENCES users(id),
        action TEXT NOT NULL,
        job_id INTEGER REFERENCES jobs(id),
        detail TEXT NOT NULL DEFAULT ''
    );
    CREATE TABLE settings (
        key TEXT PRIMARY KEY,
        value TEXT NOT NULL
    );
    """,
    # 2: where a job's exports (CSV, HTML replay, video) are: NULL (none), writing, ready, failed
    """
    ALTER TABLE jobs ADD COLUMN exports TEXT CHECK (exports IN ('writing', 'ready', 'failed'));
    CREATE INDEX jobs_exports ON jobs (exports) WHERE exports = 'writing';
    """,
    # 3: an operator's decision on a job's barrier bypass: NULL (none yet), approved, refused. Jobs waiting for the
    # arena with a bypass nobody approved go back to approved, to wait for that decision (they would run with the
    # barrier otherwise, silently)
    """
    ALTER TABLE jobs ADD COLUMN bypass_decision TEXT CHECK (bypass_decision IN ('approved', 'refused'));
    UPDATE jobs SET state = 'approved', reason = 'waiting for an operator to approve running without the barrier'
        WHERE state = 'waiting' AND verdict = 'accepted, may bypass the barrier' AND request_no_barrier = 1
        AND barrier_forbidden = 0
    """,
    # 4: tokens with an expiry, revocation and last use; sessions without a stored CSRF token (it is derived
    # from the session id, accounts.py) and with the token they were opened with; verification CPU per job
    # (per-researcher daily limit); when a job's results were deleted by the retention sweep
    """
    ALTER TABLE tokens ADD COLUMN expires REAL;
    ALTER TABLE tokens ADD COLUMN revoked REAL;
    ALTER TABLE tokens ADD COLUMN last_used REAL;
    CREATE TABLE sessions_v3 (
        hash TEXT PRIMARY KEY,
        user_id INTEGER NOT NULL REFERENCES users(id),
        token_id INTEGER REFERENCES tokens(id),
        created REAL NOT NULL,
        expires REAL NOT NULL
    );
    INSERT INTO sessions_v3 (hash, user_id, created, expires) SELECT hash, user_id, created, expires FROM sessions;
    DROP TABLE sessions;
    ALTER TABLE sessions_v3 RENAME TO sessions;
    CREATE TABLE verification_usage (
        job_id INTEGER PRIMARY KEY REFERENCES jobs(id),
        user_id INTEGER NOT NULL REFERENCES users(id),
        t REAL NOT NULL,
        cpu_s REAL NOT NULL
    );
    CREATE INDEX verification_usage_user ON verification_usage (user_id, t);
    ALTER TABLE jobs ADD COLUMN results_deleted REAL;
    """,
    # 5: job states named for what they mean (states.py): queued -> awaiting verification, approved -> awaiting
    # approval, waiting -> in arena queue; a held job's state to go back to too
    ";".join(f"UPDATE jobs SET {col} = '{new}' WHERE {col} = '{old}'"
             for old, new in RENAMED.items() for col in ("state", "held_from")),
    # 6: several arenas behind one portal (issue 30): what a job asks for (an arena by name, physical/simulated
    # robots), where it ran and which remote runner holds it; users' group and where they are told of their jobs
    # (webhook, e-mail); operators' reservations; the notifications' outbox; the remote runners' leases
    """
    ALTER TABLE jobs ADD COLUMN arena TEXT;
    ALTER TABLE jobs ADD COLUMN needs TEXT NOT NULL DEFAULT 'either' CHECK (needs IN ('either', 'physical', 'simulated'));
    ALTER TABLE jobs ADD COLUMN placed TEXT;
    ALTER TABLE jobs ADD COLUMN holder TEXT;
    CREATE INDEX jobs_placed ON jobs (placed, state);
    ALTER TABLE users ADD COLUMN grp TEXT;
    ALTER TABLE users ADD COLUMN webhook TEXT;
    ALTER TABLE users ADD COLUMN email TEXT;
    CREATE TABLE reservations (
        id INTEGER PRIMARY KEY,
        arena TEXT NOT NULL,
        user_id INTEGER REFERENCES users(id),
        grp TEXT,
        start REAL NOT NULL,
        end REAL NOT NULL,
        note TEXT NOT NULL DEFAULT '',
        created_by INTEGER REFERENCES users(id),
        created REAL NOT NULL,
        CHECK ((user_id IS NULL) != (grp IS NULL)),
        CHECK (end > start)
    );
    CREATE INDEX reservations_arena ON reservations (arena, end);
    CREATE TABLE outbox (
        id INTEGER PRIMARY KEY,
        job_id INTEGER REFERENCES jobs(id),
        user_id INTEGER NOT NULL REFERENCES users(id),
        event TEXT NOT NULL,
        channel TEXT NOT NULL CHECK (channel IN ('webhook', 'email')),
        target TEXT NOT NULL,
        body TEXT NOT NULL,
        attempts INTEGER NOT NULL DEFAULT 0,
        next_try REAL NOT NULL,
        sent REAL,
        gave_up REAL,
        error TEXT,
        created REAL NOT NULL
    );
    CREATE INDEX outbox_due ON outbox (next_try) WHERE sent IS NULL AND gave_up IS NULL;
    CREATE TABLE runners (
        arena TEXT PRIMARY KEY,
        lease TEXT NOT NULL,
        last_seen REAL NOT NULL,
        since REAL NOT NULL
    );
    """,
    # 7: sweep jobs (issue 31): the sweep's request (JSON, console.portal.sweep_job.SweepRequest); NULL: an arena job
    "ALTER TABLE jobs ADD COLUMN sweep TEXT",
    # 8: a job's script parameters (JSON object, console.portal.submission.parse_params; NULL: the defaults) and
    # the sweep job whose best point it is (issue 31: a sweep's "promote"; NULL: submitted by the researcher)
    """
    ALTER TABLE jobs ADD COLUMN params TEXT;
    ALTER TABLE jobs ADD COLUMN origin INTEGER REFERENCES jobs (id)
    """,
)


class SchemaError(RuntimeError, SwarmdeckError):
    """The database file was written by a newer swarmdeck (or is not a portal database)."""


class TransitionConflict(SwarmdeckError):
    """A conditional job transition changed nothing: the job is not in a state that allows it.

    ``state`` is the job's state now (None: no such job)."""

    def __init__(self, job_id: int, target: str, state: str | None) -> None:
        self.job_id, self.target, self.state = job_id, target, state
        if state is None:
            message = f"there is no job {job_id}"
        elif state == target:
            message = f"job {job_id} is already {state}"
        elif state in FINAL:
            message = f"job {job_id} has already ended ({state}): it cannot be {target} any more"
        else:
            message = f"job {job_id} is {state}, so it cannot be {target} now"
        super().__init__(message)


class Database:
    """The portal's database file (see the module docstring). Thread-safe: one connection per thread."""

    def __init__(self, directory: str | Path, *, busy_timeout_s: float = 10.0) -> None:
        self.directory = private_dir(Path(directory))  # 0700: other local users see nothing of it
        self.path = self.directory / FILENAME
        for path in (self.path, *(self.path.with_name(FILENAME + x) for x in ("-wal", "-shm"))):
            if path == self.path or path.exists():
                private_file(path)  # 0600 before SQLite opens it (its WAL and shm files copy the mode)
        self.busy_timeout_s = float(busy_timeout_s)
        self._local = threading.local()
        self._all: list[sqlite3.Connection] = []
        self._all_lock = threading.Lock()
        self.migrate()

    # ------------------------------------------------------------------ connections
    def connection(self) -> sqlite3.Connection:
        """This thread's connection (autocommit; rows as :class:`sqlite3.Row`)."""
        conn = getattr(self._local, "conn", None)
        if conn is None:
            conn = sqlite3.connect(self.path, timeout=self.busy_timeout_s, isolation_level=None,
                                   check_same_thread=False)
            conn.row_factory = sqlite3.Row
            conn.execute("PRAGMA journal_mode=WAL")
            conn.execute("PRAGMA foreign_keys=ON")
            conn.execute(f"PRAGMA busy_timeout={int(self.busy_timeout_s * 1000)}")
            conn.execute("PRAGMA synchronous=NORMAL")
            conn.execute("PRAGMA secure_delete=ON")  # deleted rows (sessions, old secrets) are zeroed, not left in free pages
            self._local.conn = conn
            with self._all_lock:
                self._all.append(conn)
        return conn

    @contextmanager
    def transaction(self) -> Iterator[sqlite3.Connection]:
        """``BEGIN IMMEDIATE`` … ``COMMIT`` (``ROLLBACK`` on any exception): one whole change."""
        conn = self.connection()
        conn.execute("BEGIN IMMEDIATE")
        try:
            yield conn
        except BaseException:
            conn.execute("ROLLBACK")
            raise
        conn.execute("COMMIT")

    def query(self, sql: str, params: tuple[Any, ...] | dict[str, Any] = ()) -> list[sqlite3.Row]:
        return self.connection().execute(sql, params).fetchall()

    def query_one(self, sql: str, params: tuple[Any, ...] | dict[str, Any] = ()) -> sqlite3.Row | None:
        return self.connection().execute(sql, params).fetchone()

    def close(self) -> None:
        """Close every thread's connection (the service is shutting down)."""
        with self._all_lock:
            conns, self._all = self._all, []
        for conn in conns:
            try:
                conn.close()
            except sqlite3.Error:
                pass
        self._local = threading.local()

    # ------------------------------------------------------------------ schema
    @property
    def version(self) -> int:
        row = self.query_one("SELECT version FROM schema_version")
        return 0 if row is None else int(row["version"])

    def migrate(self) -> int:
        """Apply the migrations this file has not had, in order, each in one transaction; the version."""
        conn = self.connection()
        conn.execute("CREATE TABLE IF NOT EXISTS schema_version (version INTEGER NOT NULL)")
        current = self.version
        if current > len(MIGRATIONS):
            raise SchemaError(f"{self.path} has schema version {current}, newer than this swarmdeck "
                              f"({len(MIGRATIONS)}): upgrade swarmdeck")
        for version in range(current + 1, len(MIGRATIONS) + 1):
            with self.transaction() as tx:
                for statement in MIGRATIONS[version - 1].split(";"):
                    if statement.strip():
                        tx.execute(statement)
                tx.execute("DELETE FROM schema_version")
                tx.execute("INSERT INTO schema_version (version) VALUES (?)", (version,))
        return self.version

    def check(self) -> str:
        """SQLite's own integrity check: ``"ok"`` for an intact file."""
        row = self.query_one("PRAGMA integrity_check")
        return "no answer" if row is None else str(row[0])

    # ------------------------------------------------------------------ jobs' state machine
    def transition(self, tx: sqlite3.Connection, job_id: int, target: str, *, sources: tuple[str, ...] | None = None,
                   **columns: Any) -> None:
        """Move job ``job_id`` to ``target`` inside ``tx`` if it is in one of ``sources`` (default: every
        state :data:`TRANSITIONS` allows to reach ``target``), setting ``columns`` too; else
        :class:`TransitionConflict` (the caller's transaction rolls back)."""
        if target not in STATES:
            raise ValueError(f"unknown job state {target!r}")
        allowed = tuple(s for s, targets in TRANSITIONS.items() if target in targets)
        sources = allowed if sources is None else tuple(s for s in sources if s in allowed)
        if not sources:
            raise ValueError(f"no state may move to {target!r}")
        sets = ", ".join(["state = ?", "updated = ?"] + [f"{name} = ?" for name in columns])
        marks = ", ".join("?" * len(sources))
        cur = tx.execute(f"UPDATE jobs SET {sets} WHERE id = ? AND state IN ({marks})",
                         (target, time.time(), *columns.values(), job_id, *sources))
        if cur.rowcount != 1:
            row = tx.execute("SELECT state FROM jobs WHERE id = ?", (job_id,)).fetchone()
            raise TransitionConflict(job_id, target, None if row is None else row["state"])

    # ------------------------------------------------------------------ settings
    def setting(self, key: str, default: str) -> str:
        row = self.query_one("SELECT value FROM settings WHERE key = ?", (key,))
        return default if row is None else str(row["value"])

    @staticmethod
    def set_setting(tx: sqlite3.Connection, key: str, value: str) -> None:
        tx.execute("INSERT INTO settings (key, value) VALUES (?, ?) "
                   "ON CONFLICT(key) DO UPDATE SET value = excluded.value", (key, value))
