"""The lab's rows beside the jobs (issue 30): reservations, the notifications' outbox, remote runners' leases and
where each user is told of their jobs (webhook, e-mail) and their group. Every SQL statement on ``reservations``,
``outbox``, ``runners`` and the users' ``grp``/``webhook``/``email`` columns (migration 6 of :mod:`.db`).

Reads run on the thread's connection; changes take the caller's transaction ``tx`` (or open their own where
they say so), as in :mod:`.jobstore`.
"""
from __future__ import annotations

import builtins
import sqlite3
import time
from dataclasses import dataclass
from typing import Any

from swarmdeck.console.portal.db import Database

Tx = sqlite3.Connection


@dataclass(frozen=True)
class Reservation:
    """An operator's booking: ``arena`` for a user (``user``) or a group (``group``) over [start, end) UNIX s."""

    id: int
    arena: str
    user_id: int | None
    user: str | None
    group: str | None
    start: float
    end: float
    note: str
    created_by: str | None

    def to_dict(self) -> dict[str, Any]:
        return {"id": self.id, "arena": self.arena, "user": self.user, "group": self.group, "start": self.start,
                "end": self.end, "note": self.note, "created_by": self.created_by}


@dataclass(frozen=True)
class Notice:
    """One notification in the outbox: where it goes (``channel`` webhook | email, ``target`` URL | address),
    what it says (``body``: JSON text) and how often it was tried."""

    id: int
    job_id: int | None
    user_id: int
    event: str
    channel: str
    target: str
    body: str
    attempts: int


_RES_SELECT = ("SELECT r.*, u.name AS user, c.name AS creator FROM reservations r LEFT JOIN users u ON u.id = r.user_id "
               "LEFT JOIN users c ON c.id = r.created_by")


def _reservation(r: sqlite3.Row) -> Reservation:
    return Reservation(id=int(r["id"]), arena=str(r["arena"]), user_id=r["user_id"], user=r["user"], group=r["grp"],
                       start=float(r["start"]), end=float(r["end"]), note=str(r["note"]), created_by=r["creator"])


class LabStore:
    """The lab's rows (module docstring) of one :class:`~.db.Database`."""

    def __init__(self, db: Database) -> None:
        self.db = db

    # ------------------------------------------------------------------ users: group and notification targets
    def targets(self, user_id: int, tx: Tx | None = None) -> tuple[str | None, str | None]:
        """(webhook URL, e-mail address) of the user (None: not set)."""
        conn = tx if tx is not None else self.db.connection()
        row = conn.execute("SELECT webhook, email FROM users WHERE id = ?", (int(user_id),)).fetchone()
        return (None, None) if row is None else (row["webhook"], row["email"])

    def set_targets(self, user_id: int, webhook: str | None, email: str | None) -> None:
        with self.db.transaction() as tx:
            tx.execute("UPDATE users SET webhook = ?, email = ? WHERE id = ?", (webhook, email, int(user_id)))

    def group_of(self, user_id: int) -> str | None:
        row = self.db.query_one("SELECT grp FROM users WHERE id = ?", (int(user_id),))
        return None if row is None else row["grp"]

    def set_group(self, tx: Tx, user_id: int, group: str | None) -> None:
        tx.execute("UPDATE users SET grp = ? WHERE id = ?", (group, int(user_id)))

    def members(self, group: str) -> builtins.list[int]:
        return [int(r["id"]) for r in self.db.query("SELECT id FROM users WHERE grp = ?", (group,))]

    # ------------------------------------------------------------------ reservations
    def reservations(self, since: float, tx: Tx | None = None) -> builtins.list[Reservation]:
        """The reservations that end after ``since``, by start."""
        conn = tx if tx is not None else self.db.connection()
        rows = conn.execute(f"{_RES_SELECT} WHERE r.end > ? ORDER BY r.start, r.id", (float(since),)).fetchall()
        return [_reservation(r) for r in rows]

    def reservation(self, res_id: int) -> Reservation | None:
        row = self.db.query_one(f"{_RES_SELECT} WHERE r.id = ?", (int(res_id),))
        return None if row is None else _reservation(row)

    def overlapping(self, tx: Tx, arena: str, start: float, end: float) -> Reservation | None:
        """A reservation of ``arena`` that overlaps [start, end) (None: none)."""
        row = tx.execute(f"{_RES_SELECT} WHERE r.arena = ? AND r.start < ? AND ? < r.end ORDER BY r.start LIMIT 1",
                         (arena, float(end), float(start))).fetchone()
        return None if row is None else _reservation(row)

    def add_reservation(self, tx: Tx, *, arena: str, user_id: int | None, group: str | None, start: float,
                        end: float, note: str, created_by: int) -> int:
        cur = tx.execute("INSERT INTO reservations (arena, user_id, grp, start, end, note, created_by, created) "
                         "VALUES (?, ?, ?, ?, ?, ?, ?, ?)",
                         (arena, user_id, group, float(start), float(end), note, int(created_by), time.time()))
        return int(cur.lastrowid or 0)

    def delete_reservation(self, tx: Tx, res_id: int) -> bool:
        return tx.execute("DELETE FROM reservations WHERE id = ?", (int(res_id),)).rowcount == 1

    # ------------------------------------------------------------------ the outbox
    def enqueue(self, tx: Tx, *, job_id: int | None, user_id: int, event: str, channel: str, target: str,
                body: str, now: float) -> None:
        """A notification to send (the sender: :mod:`.notify`), committed with the change it reports."""
        tx.execute("INSERT INTO outbox (job_id, user_id, event, channel, target, body, next_try, created) "
                   "VALUES (?, ?, ?, ?, ?, ?, ?, ?)", (job_id, int(user_id), event, channel, target, body, now, now))

    def due(self, now: float, limit: int = 20) -> builtins.list[Notice]:
        """Notifications not yet sent nor given up whose next try is due, oldest first."""
        rows = self.db.query("SELECT * FROM outbox WHERE sent IS NULL AND gave_up IS NULL AND next_try <= ? "
                             "ORDER BY next_try, id LIMIT ?", (float(now), int(limit)))
        return [Notice(id=int(r["id"]), job_id=r["job_id"], user_id=int(r["user_id"]), event=str(r["event"]),
                       channel=str(r["channel"]), target=str(r["target"]), body=str(r["body"]),
                       attempts=int(r["attempts"])) for r in rows]

    def next_due(self) -> float | None:
        row = self.db.query_one("SELECT MIN(next_try) AS t FROM outbox WHERE sent IS NULL AND gave_up IS NULL")
        return None if row is None or row["t"] is None else float(row["t"])

    def mark_sent(self, notice_id: int, now: float) -> None:
        with self.db.transaction() as tx:
            tx.execute("UPDATE outbox SET sent = ?, attempts = attempts + 1, error = NULL WHERE id = ?",
                       (float(now), int(notice_id)))

    def mark_failed(self, notice_id: int, error: str, next_try: float | None, now: float) -> None:
        """A try failed: try again at ``next_try`` (None: give up)."""
        with self.db.transaction() as tx:
            tx.execute("UPDATE outbox SET attempts = attempts + 1, error = ?, next_try = COALESCE(?, next_try), "
                       "gave_up = ? WHERE id = ?",
                       (error[:1000], next_try, None if next_try is not None else float(now), int(notice_id)))

    def notices(self, user_id: int | None = None, limit: int = 100) -> builtins.list[dict[str, Any]]:
        """The latest notifications (a user's, or everyone's) with how they went."""
        where, args = ("WHERE user_id = ?", (int(user_id),)) if user_id is not None else ("", ())
        rows = self.db.query(f"SELECT id, job_id, event, channel, target, attempts, sent, gave_up, error, created "
                             f"FROM outbox {where} ORDER BY id DESC LIMIT ?", (*args, int(limit)))
        return [dict(r) for r in rows]

    # ------------------------------------------------------------------ remote runners' leases
    def lease(self, arena: str, tx: Tx | None = None) -> tuple[str, float] | None:
        """(lease, last seen UNIX s) of the runner holding ``arena`` (None: none ever connected)."""
        conn = tx if tx is not None else self.db.connection()
        row = conn.execute("SELECT lease, last_seen FROM runners WHERE arena = ?", (arena,)).fetchone()
        return None if row is None else (str(row["lease"]), float(row["last_seen"]))

    def take_lease(self, tx: Tx, arena: str, lease: str, now: float) -> None:
        tx.execute("INSERT INTO runners (arena, lease, last_seen, since) VALUES (?, ?, ?, ?) ON CONFLICT(arena) DO "
                   "UPDATE SET lease = excluded.lease, last_seen = excluded.last_seen, since = excluded.since",
                   (arena, lease, now, now))

    def touch(self, arena: str, lease: str, now: float, seen_after: float) -> bool:
        """The runner holding ``lease`` is alive; False when the lease is not ``arena``'s or ran out (its runner
        was last heard from before ``seen_after``: a runner coming back after that must connect again)."""
        with self.db.transaction() as tx:
            cur = tx.execute("UPDATE runners SET last_seen = ? WHERE arena = ? AND lease = ? AND last_seen >= ?",
                             (now, arena, lease, seen_after))
        return cur.rowcount == 1

    def drop_lease(self, tx: Tx, arena: str) -> None:
        tx.execute("DELETE FROM runners WHERE arena = ?", (arena,))
