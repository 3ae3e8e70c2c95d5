"""Job states are named for what they mean, in one place (issue 26 item 14): the JobState enum is the database's
state machine, the client's final states and what the API shows; a version-4 database's jobs are renamed
(queued -> awaiting verification, approved -> awaiting approval, waiting -> in arena queue); the README documents
every state in one table."""
from __future__ import annotations

import sqlite3
from pathlib import Path

from swarmdeck.console.portal import client, db
from swarmdeck.console.portal.states import ACTIVE, FINAL, JobState

ROOT = Path(__file__).resolve().parents[2]


def test_the_state_machine_client_and_service_use_the_one_enum():
    assert db.STATES == tuple(JobState)
    assert all(isinstance(s, JobState) for s in db.TRANSITIONS) and all(
        isinstance(t, JobState) for targets in db.TRANSITIONS.values() for t in targets)
    assert client.FINAL_STATES is FINAL and db.FINAL is FINAL and db.ACTIVE is ACTIVE
    assert not {"queued", "approved", "waiting"} & {s.value for s in JobState}  # the misleading names are gone
    assert JobState.IN_ARENA_QUEUE == "in arena queue" and isinstance(JobState.DONE, str)  # JSON and SQL stay strings


def test_a_version_4_database_gets_the_new_names(tmp_path):
    conn = sqlite3.connect(tmp_path / db.FILENAME)
    for migration in db.MIGRATIONS[:4]:
        conn.executescript(migration)
    conn.executescript("CREATE TABLE schema_version (version INTEGER NOT NULL); INSERT INTO schema_version VALUES (4);"
                       "INSERT INTO users (name, role, created) VALUES ('alice', 'researcher', 0);")
    rows = [("a", "queued", None), ("b", "approved", None), ("c", "waiting", None), ("d", "held", "waiting"),
            ("e", "done", None), ("f", "setting up", None)]
    conn.executemany("INSERT INTO jobs (user_id, name, state, held_from, kind, script_name, entry, n_robots, duration, "
                     "priority, created, updated) VALUES (1, ?, ?, ?, 'py', 'a.py', 'script.py', 2, 1.0, 1, 0, 0)", rows)
    conn.commit()
    conn.close()
    d = db.Database(tmp_path)
    assert d.version == len(db.MIGRATIONS) >= 5 and d.check() == "ok"
    got = {r["name"]: (r["state"], r["held_from"]) for r in d.query("SELECT name, state, held_from FROM jobs")}
    assert got == {"a": ("awaiting verification", None), "b": ("awaiting approval", None),
                   "c": ("in arena queue", None), "d": ("held", "in arena queue"), "e": ("done", None),
                   "f": ("setting up", None)}
    d.close()


def test_the_api_says_what_a_job_waits_for(portal):  # noqa: F811
    svc = portal.service
    with portal.client("op1") as op:
        op.put("/api/operator/settings", json={"manual_approval": True})
    jid = portal.submit("alice").json()["id"]
    with portal.client("alice") as c:
        assert c.get(f"/api/jobs/{jid}").json()["state"] in ("awaiting verification", "verifying")
    svc.finish_verification(svc.claim_for_verification().id, "accepted", 1.0, [])
    with portal.client("alice") as c:
        assert c.get(f"/api/jobs/{jid}").json()["state"] == "awaiting approval"  # an operator must approve it
    with portal.client("op1") as op:
        job = op.post(f"/api/operator/jobs/{jid}/approve").json()
    assert job["state"] == "in arena queue" and job["position"] == 0


def test_the_readme_documents_every_state_in_one_table():
    readme = (ROOT / "README.md").read_text()
    table = [line for line in readme.splitlines() if line.startswith("| `")]
    documented = {word for line in table for word in line.split("|")[1].split("`")[1::2]}
    assert {s.value for s in JobState} <= documented
