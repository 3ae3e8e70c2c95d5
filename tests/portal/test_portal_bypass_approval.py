"""Running without the barrier needs an operator's approval of that job's bypass, whatever the manual-approval switch
says: a "may bypass" verdict leaves the job approved and waiting for that decision (switching manual approval off,
releasing a held job, a plain approve: none of them lets it through), the operator page shows verdict, S and the
report beside the approve/refuse buttons, each decision is audited, and a database from before this rule (a job
waiting for the arena with a bypass nobody approved) is migrated back to waiting for the decision."""
import sqlite3

from portal_fixtures import sign_in

from swarmdeck.console.portal.db import MIGRATIONS, Database
from swarmdeck.console.portal.service import BYPASS_VERDICT, BYPASS_WAIT


def verified(svc, jid, verdict=BYPASS_VERDICT):
    """What verification with ``verdict`` does to job ``jid``."""
    with svc.db.transaction() as tx:
        svc.db.transition(tx, jid, "verifying")
    svc.finish_verification(jid, verdict, 1.0, [])
    return svc.job_state(jid)


def test_a_may_bypass_verdict_waits_for_an_operator_whatever_the_switches_say(portal):
    svc = portal.service
    asks = portal.submit("alice", duration=1.0, no_barrier=True).json()["id"]
    plain = portal.submit("alice", duration=1.0).json()["id"]
    assert verified(svc, asks) == "awaiting approval" and verified(svc, plain) == "in arena queue"  # manual approval is off
    with portal.client("alice") as c:
        job = c.get(f"/api/jobs/{asks}").json()
        assert job["reason"] == BYPASS_WAIT and job["bypass_pending"] and job["bypass_decision"] is None
    with portal.client("op1") as op:
        assert op.put("/api/operator/settings", json={"manual_approval": True}).status_code == 200
        assert op.put("/api/operator/settings", json={"manual_approval": False}).status_code == 200
        assert svc.job_state(asks) == "awaiting approval"  # switching manual approval off does not release it
        assert op.post(f"/api/operator/jobs/{asks}/hold").json()["state"] == "held"
        assert op.post(f"/api/operator/jobs/{asks}/release").json()["state"] == "awaiting approval"  # nor a release
        r = op.post(f"/api/operator/jobs/{asks}/approve")
        assert r.status_code == 409 and "approve or refuse that bypass" in r.json()["error"]
        r = op.post(f"/api/operator/jobs/{plain}/bypass", json={"approve": True})
        assert r.status_code == 409  # a job that did not ask (or may not) has nothing to decide
        r = op.post(f"/api/operator/jobs/{asks}/bypass", json={})
        assert r.status_code == 422 and r.json()["field"] == "approve"
        # an operator forbidding the bypass decides it too: the job runs with the barrier
        assert op.post(f"/api/operator/jobs/{asks}/barrier", json={"forbid": True}).json()["state"] == "in arena queue"
        again = op.post(f"/api/operator/jobs/{asks}/barrier", json={"forbid": False}).json()
        assert again["state"] == "awaiting approval" and again["reason"] == BYPASS_WAIT
        done = op.post(f"/api/operator/jobs/{asks}/bypass", json={"approve": True}).json()
        assert done["state"] == "in arena queue" and done["bypass_decision"] == "approved" and done["reason"] is None
        assert svc.bypass_allowed(done) and not svc.bypass_allowed(op.get(f"/api/jobs/{plain}").json())
        actions = [e["action"] for e in op.get("/api/operator/audit").json()]
        assert actions[:3] == ["approve barrier bypass", "allow barrier bypass", "forbid barrier bypass"]


def test_under_manual_approval_a_refused_bypass_still_needs_the_usual_approval(portal):
    svc = portal.service
    with portal.client("op1") as op:
        op.put("/api/operator/settings", json={"manual_approval": True})
        jid = portal.submit("bob", duration=1.0, no_barrier=True).json()["id"]
        assert verified(svc, jid) == "awaiting approval"
        refused = op.post(f"/api/operator/jobs/{jid}/bypass", json={"approve": False}).json()
        assert refused["state"] == "awaiting approval" and refused["barrier_forbidden"] and not refused["bypass_pending"]
        assert op.post(f"/api/operator/jobs/{jid}/approve").json()["state"] == "in arena queue"
        assert not svc.bypass_allowed(op.get(f"/api/jobs/{jid}").json())


def test_the_operator_page_shows_verdict_score_and_report_beside_the_bypass_buttons(portal):
    svc = portal.service
    jid = portal.submit("alice", duration=1.0, no_barrier=True).json()["id"]
    verified(svc, jid)
    op, csrf = sign_in(portal, "op1")
    try:
        page = op.get("/operator").text
        assert BYPASS_VERDICT in page and "S = 1.0000" in page and f'href="/jobs/{jid}/report"' in page
        assert f'data-action="bypass-approve" data-job="{jid}"' in page
        assert f'data-action="bypass-refuse" data-job="{jid}"' in page
        assert f'data-action="approve" data-job="{jid}"' not in page  # no plain approve for it
        assert op.post(f"/operator/jobs/{jid}/bypass-approve", data={"csrf": csrf}).status_code == 303
        assert svc.job_state(jid) == "in arena queue"
    finally:
        op.close()
    researcher, _ = sign_in(portal, "alice")
    try:
        other = portal.submit("alice", duration=1.0, no_barrier=True).json()["id"]
        verified(svc, other)
        assert BYPASS_WAIT in researcher.get(f"/jobs/{other}").text
    finally:
        researcher.close()


def test_a_version_2_database_sends_unapproved_bypasses_back_to_wait_for_an_operator(tmp_path):
    conn = sqlite3.connect(tmp_path / "portal.sqlite3")  # as the portal before this rule left it
    conn.executescript(MIGRATIONS[0])
    conn.executescript(MIGRATIONS[1])
    conn.executescript("CREATE TABLE schema_version (version INTEGER NOT NULL); INSERT INTO schema_version VALUES (2);"
                       "INSERT INTO users (name, role, created) VALUES ('alice', 'researcher', 0);")
    rows = [("asks", "waiting", BYPASS_VERDICT, 1, 0), ("forbidden", "waiting", BYPASS_VERDICT, 1, 1),
            ("plain", "waiting", "accepted", 1, 0), ("ran", "done", BYPASS_VERDICT, 1, 0)]
    conn.executemany("INSERT INTO jobs (user_id, name, state, kind, script_name, entry, n_robots, duration, priority, "
                     "created, updated, verdict, request_no_barrier, barrier_forbidden) "
                     "VALUES (1, ?, ?, 'py', 'a.py', 'script.py', 2, 1.0, 1, 0, 0, ?, ?, ?)", rows)
    conn.commit()
    conn.close()
    db = Database(tmp_path)
    assert db.version == len(MIGRATIONS) and db.check() == "ok"
    got = {r["name"]: (r["state"], r["reason"], r["bypass_decision"])
           for r in db.query("SELECT name, state, reason, bypass_decision FROM jobs")}
    assert got == {"asks": ("awaiting approval", BYPASS_WAIT, None), "forbidden": ("in arena queue", None, None),
                   "plain": ("in arena queue", None, None), "ran": ("done", None, None)}
    db.close()
