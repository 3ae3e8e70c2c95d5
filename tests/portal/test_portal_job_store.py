"""The jobs' rows have one home (issue 25 item 5): only the job store (and the database's schema, and the accounts'
own tables) speaks SQL in the portal; the portal and the CLI client name job states only through JobState; and a
data folder from an old swarmdeck (schema version 1, the old state names) opens and serves its jobs as typed Jobs."""
from __future__ import annotations

import re
import sqlite3
from pathlib import Path

from swarmdeck.console.portal import db
from swarmdeck.console.portal.job import ExportState, Job
from swarmdeck.console.portal.service import PortalConfig, PortalService
from swarmdeck.console.portal.states import JobState

ROOT = Path(__file__).resolve().parents[2]
PORTAL = ROOT / "console" / "portal"
SQL = re.compile(r"\b(SELECT\b.+\bFROM|UPDATE\s+\w+\s+SET|INSERT\s+(OR\s+\w+\s+)?INTO|DELETE\s+FROM)\b")
#: the modules that may hold SQL: the schema and its connections, the jobs' store, the accounts' tables
SQL_HOMES = {"db.py", "jobstore.py", "accounts.py", "labstore.py"}
CLIENT = [ROOT / "console" / "cli" / f"{name}.py" for name in ("submit", "jobs", "cancel", "results", "_client")]
#: states whose names say nothing else in this code (a sandbox run also ends "cancelled", an export "failed")
UNAMBIGUOUS = [s for s in JobState if " " in s.value or s in (JobState.VERIFYING, JobState.HELD)]


def test_only_the_store_the_schema_and_the_accounts_speak_sql():
    offenders = [p.name for p in sorted(PORTAL.glob("*.py")) if p.name not in SQL_HOMES and SQL.search(p.read_text())]
    assert offenders == []
    assert SQL.search((PORTAL / "jobstore.py").read_text())  # the pattern finds what it is for


def test_the_portal_and_the_client_name_job_states_only_through_the_enum():
    literal = re.compile("|".join(rf"""(["']){re.escape(s.value)}\1""" for s in UNAMBIGUOUS))
    files = [p for p in sorted(PORTAL.glob("*.py")) if p.name != "states.py"] + CLIENT
    found = [f"{p.name}:{k + 1}" for p in files for k, line in enumerate(p.read_text().splitlines())
             if literal.search(line.split("#")[0]) and not line.lstrip().startswith(("*", "``"))]
    assert found == []


def test_an_old_data_folder_opens_and_serves_its_jobs_as_typed_jobs(tmp_path):
    data = tmp_path / "lab"
    data.mkdir()
    conn = sqlite3.connect(data / db.FILENAME)
    conn.executescript(db.MIGRATIONS[0])
    conn.executescript("CREATE TABLE schema_version (version INTEGER NOT NULL); INSERT INTO schema_version VALUES (1);"
                       "INSERT INTO users (name, role, created) VALUES ('olga', 'operator', 0);")
    rows = [("a", "queued", None, None), ("b", "waiting", None, None), ("c", "held", "approved", None),
            ("d", "done", None, "[[0, 0, 0], [0.5, 0, 1]]")]
    conn.executemany("INSERT INTO jobs (user_id, name, state, held_from, kind, script_name, entry, n_robots, duration, "
                     "initial_poses, priority, created, updated) VALUES (1, ?, ?, ?, 'py', 'a.py', 'script.py', 2, 1.0, "
                     "?, 1, 0, 0)", rows)
    conn.commit()
    conn.close()
    svc = PortalService(PortalConfig(data=data))
    try:
        olga = svc.accounts.user_named("olga")
        jobs = {j.name: j for j in svc.jobs(olga)}
        assert all(isinstance(j, Job) and isinstance(j.state, JobState) for j in jobs.values())
        assert jobs["a"].state is JobState.AWAITING_VERIFICATION and jobs["b"].position == 0
        assert jobs["c"].state is JobState.HELD and jobs["c"].held_from is JobState.AWAITING_APPROVAL
        assert jobs["d"].initial_poses == ((0.0, 0.0, 0.0), (0.5, 0.0, 1.0)) and jobs["d"].exports is None
        assert svc.release(olga, jobs["c"].id).state is JobState.IN_ARENA_QUEUE  # manual approval is off
        svc.set_exports(jobs["d"].id, ExportState.READY)
        assert svc.job(olga, jobs["d"].id).to_dict()["exports"] == "ready"
    finally:
        svc.close()
