"""The portal's SQLite file: schema versioned and migrated once, WAL, and job transitions as conditional updates
(of two operators acting on one job at once exactly one succeeds)."""
import sqlite3
import threading

import pytest

from swarmdeck.console.portal.accounts import Accounts
from swarmdeck.console.portal.db import MIGRATIONS, Database, SchemaError, TransitionConflict


def test_a_new_file_is_migrated_in_wal_mode_and_reopening_keeps_the_data(tmp_path):
    db = Database(tmp_path)
    assert db.version == len(MIGRATIONS)
    assert db.query_one("PRAGMA journal_mode")[0] == "wal"
    assert db.query_one("PRAGMA foreign_keys")[0] == 1
    Accounts(db).add_user("alice", "researcher")
    db.close()
    again = Database(tmp_path)
    assert again.version == len(MIGRATIONS) and again.check() == "ok"
    assert [u.name for u in Accounts(again).users()] == ["alice"]


def test_a_version_1_file_gains_the_exports_column_and_keeps_its_jobs(tmp_path):
    conn = sqlite3.connect(tmp_path / "portal.sqlite3")  # as the first portal left it
    conn.executescript(MIGRATIONS[0])
    conn.executescript("CREATE TABLE schema_version (version INTEGER NOT NULL); INSERT INTO schema_version VALUES (1);"
                       "INSERT INTO users (name, role, created) VALUES ('alice', 'researcher', 0);"
                       "INSERT INTO jobs (user_id, name, state, kind, script_name, entry, n_robots, duration, priority,"
                       " created, updated) VALUES (1, 'old', 'done', 'py', 'a.py', 'script.py', 2, 1.0, 1, 0, 0);")
    conn.close()
    db = Database(tmp_path)
    assert db.version == len(MIGRATIONS) and db.check() == "ok"
    row = db.query_one("SELECT name, state, exports FROM jobs")
    assert tuple(row) == ("old", "done", None)
    with pytest.raises(sqlite3.IntegrityError), db.transaction() as tx:
        tx.execute("UPDATE jobs SET exports = 'sometime'")


def test_a_file_from_a_newer_swarmdeck_is_refused(tmp_path):
    Database(tmp_path).close()
    conn = sqlite3.connect(tmp_path / "portal.sqlite3")
    conn.execute("UPDATE schema_version SET version = 99")
    conn.commit()
    conn.close()
    with pytest.raises(SchemaError, match="schema version 99, newer"):
        Database(tmp_path)


def test_a_failing_transaction_leaves_nothing_behind(tmp_path):
    db = Database(tmp_path)
    with pytest.raises(RuntimeError):
        with db.transaction() as tx:
            tx.execute("INSERT INTO users (name, role, created) VALUES ('x', 'researcher', 0)")
            raise RuntimeError("crash mid-way")
    assert db.query("SELECT * FROM users") == []


def _job(db, state):
    with db.transaction() as tx:
        uid = tx.execute("INSERT INTO users (name, role, created) VALUES ('u', 'operator', 0)").lastrowid
        return tx.execute("INSERT INTO jobs (user_id, name, state, kind, script_name, entry, n_robots, duration, "
                          "priority, created, updated) VALUES (?, 'j', ?, 'py', 's.py', 'script.py', 2, 1.0, 1, 0, 0)",
                          (uid, state)).lastrowid


def test_two_threads_moving_one_job_at_once_give_one_success_and_one_conflict(tmp_path):
    db = Database(tmp_path)
    job = _job(db, "awaiting approval")
    start = threading.Barrier(2)
    outcomes = []

    def approve():
        start.wait()
        try:
            with db.transaction() as tx:
                db.transition(tx, job, "in arena queue", sources=("awaiting approval",))
            outcomes.append("ok")
        except TransitionConflict as exc:
            outcomes.append(exc.state)

    threads = [threading.Thread(target=approve) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(outcomes) == ["in arena queue", "ok"]
    assert db.query_one("SELECT state FROM jobs WHERE id = ?", (job,))["state"] == "in arena queue"


def test_a_transition_the_state_machine_does_not_allow_is_a_conflict(tmp_path):
    db = Database(tmp_path)
    job = _job(db, "done")
    with pytest.raises(TransitionConflict, match=rf"job {job} has already ended \(done\): it cannot be cancelled any more"):
        with db.transaction() as tx:
            db.transition(tx, job, "cancelled")
    with pytest.raises(ValueError, match="unknown job state"):
        with db.transaction() as tx:
            db.transition(tx, job, "exploded")


def test_a_version_2_file_keeps_its_tokens_and_sessions_and_loses_the_stored_csrf_tokens(tmp_path):
    from swarmdeck.console.portal.accounts import digest

    token, sid = "sdk_" + "t" * 43, "s" * 43
    conn = sqlite3.connect(tmp_path / "portal.sqlite3")  # as the portal before token expiry left it
    for migration in MIGRATIONS[:2]:
        conn.executescript(migration)
    conn.executescript("CREATE TABLE schema_version (version INTEGER NOT NULL); INSERT INTO schema_version VALUES (2);"
                       "INSERT INTO users (name, role, created) VALUES ('alice', 'researcher', 0);")
    conn.execute("INSERT INTO tokens (user_id, hash, created) VALUES (1, ?, 0)", (digest(token),))
    conn.execute("INSERT INTO sessions (hash, user_id, csrf, created, expires) VALUES (?, 1, ?, 0, 1e12)",
                 (digest(sid), "CLEAR-CSRF-TOKEN-OF-OLD"))
    conn.commit()
    conn.close()
    db = Database(tmp_path)
    assert db.version == len(MIGRATIONS) and db.check() == "ok"
    accounts = Accounts(db)
    assert accounts.user_for_token(token).name == "alice"
    [info] = accounts.tokens("alice")
    assert (info.expires, info.revoked) == (None, None) and info.last_used is not None
    session = accounts.session(sid)  # still signed in
    assert session.user.name == "alice" and session.csrf == accounts.csrf_for(sid) != "CLEAR-CSRF-TOKEN-OF-OLD"
    assert "csrf" not in [r["name"] for r in db.query("PRAGMA table_info(sessions)")]
    db.close()
    raw = b"".join(p.read_bytes() for p in tmp_path.glob("portal.sqlite3*"))
    assert b"CLEAR-CSRF-TOKEN-OF-OLD" not in raw  # not even in a free page
