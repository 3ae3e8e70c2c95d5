"""Per-researcher limits on real uvicorn and SQLite: unfinished jobs (default 25: the 26th submission in a row is
refused, 429, naming the limit and the count), verification CPU a day (429), results on disk (403). Other
researchers and operators are not held up by one researcher's limit."""
import pytest
from portal_fixtures import make_portal, sign_in

from swarmdeck.console.portal.quotas import Quotas
from swarmdeck.console.sandbox.confinement import probe


def test_the_26th_submission_in_a_row_is_refused_naming_the_limit(portal):
    assert Quotas().max_unfinished_jobs == 25  # the documented default
    ids = []
    for k in range(25):
        r = portal.submit("alice", name=f"run{k}")
        assert r.status_code == 201, (k, r.text)
        ids.append(r.json()["id"])
    r = portal.submit("alice", name="run25")
    assert r.status_code == 429 and r.json() == {
        "error": "you have 25 jobs not yet finished (awaiting verification or approval, verifying, in arena queue or "
                 "running); the limit is 25: "
                 "wait for one to end, or cancel one", "field": "max_unfinished_jobs"}
    assert len(portal.service.db.query("SELECT id FROM jobs")) == 25  # nothing stored for the refused one
    assert portal.submit("bob").status_code == 201  # bob has his own count
    assert portal.submit("op1").status_code == 201  # operators are not limited
    with portal.client("alice") as c:
        assert c.post(f"/api/jobs/{ids[0]}/cancel").status_code == 200
    assert portal.submit("alice", name="run26").status_code == 201  # a finished job frees a place
    with portal.client("op1") as c:
        assert c.get("/api/operator/stats").json()["rejected"]["by_field"]["429 max_unfinished_jobs"] == 1


def test_the_submit_page_shows_the_limit(portal):
    for k in range(25):
        assert portal.submit("alice", name=f"run{k}").status_code == 201
    alice, csrf = sign_in(portal, "alice")
    r = alice.post("/submit", data={"csrf": csrf, "name": "one more", "robots": "2", "duration": "1"},
                   files={"script": ("spin.py", b"def experiment(arena):\n    arena.step()\n")})
    assert r.status_code == 429 and "you have 25 jobs not yet finished" in r.text and "the limit is 25" in r.text


def test_verification_cpu_over_the_daily_limit_refuses_new_jobs(tmp_path):
    p = make_portal(tmp_path, quotas=Quotas(verify_cpu_s_per_day=100.0), fleet=6, max_duration=60.0,
                    max_upload_bytes=64 << 10)
    try:
        first = p.submit("alice").json()["id"]
        p.service.record_verification_cpu(first, 60.0)  # what the verification worker records
        second = p.submit("alice").json()["id"]
        p.service.record_verification_cpu(second, 45.5)
        r = p.submit("alice")
        assert r.status_code == 429 and r.json()["field"] == "verify_cpu_s_per_day", r.text
        assert "used 106 CPU s in the last 24 h; the limit is 100 CPU s a day" in r.json()["error"]
        assert "accepted again from" in r.json()["error"]
        assert p.submit("bob").status_code == 201
        with p.service.db.transaction() as tx:  # a day later
            tx.execute("UPDATE verification_usage SET t = t - 86401")
        assert p.submit("alice").status_code == 201
    finally:
        p.server.stop()
        p.service.close()


def test_results_over_the_disk_quota_refuse_new_jobs_with_403(tmp_path):
    p = make_portal(tmp_path, quotas=Quotas(results_bytes=100_000), fleet=6, max_duration=60.0,
                    max_upload_bytes=64 << 10)
    try:
        jid = p.submit("alice").json()["id"]
        (p.service.job_dir(jid) / "recording.mcap").write_bytes(b"\0" * 120_000)  # a run's results
        r = p.submit("alice")
        assert r.status_code == 403 and r.json()["field"] == "results_bytes", r.text
        assert "your jobs' files take 120.2 kB; the limit is 100.0 kB" in r.json()["error"]
        assert p.submit("bob").status_code == 201
        assert p.submit("op1").status_code == 201
    finally:
        p.server.stop()
        p.service.close()


@pytest.mark.parametrize("bad", [float("nan"), -1.0, float("inf")])
def test_a_nonsense_cpu_figure_is_not_recorded(portal, bad):
    jid = portal.submit("alice").json()["id"]
    portal.service.record_verification_cpu(jid, bad)
    assert portal.service.db.query("SELECT * FROM verification_usage") == []


@pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
def test_the_verification_worker_charges_each_jobs_cpu_to_its_owner(portal):
    from portal_fixtures import wait_for_state

    from swarmdeck.console.portal.workers import VerificationWorkers
    from swarmdeck.console.sandbox.executors import LocalPoolExecutor

    workers = VerificationWorkers(portal.service, LocalPoolExecutor(1), poll_s=0.2).start()
    try:
        jid = portal.submit("alice", robots=2, duration=1.0).json()["id"]
        with portal.client("alice") as c:
            wait_for_state(c, jid, ("in arena queue", "rejected"), timeout=180)
    finally:
        workers.stop()
    [row] = portal.service.db.query("SELECT job_id, user_id, cpu_s FROM verification_usage")
    alice = portal.service.accounts.user_named("alice")
    assert (row["job_id"], row["user_id"]) == (jid, alice.id) and 0.0 < row["cpu_s"] < 600.0


def test_a_researcher_sees_where_they_stand(portal):
    jid = portal.submit("alice").json()["id"]
    portal.service.record_verification_cpu(jid, 12.5)
    with portal.client("alice") as c:
        limits = c.get("/api/me").json()["limits"]
    assert limits["unfinished_jobs"] == {"used": 1, "limit": 25}
    assert limits["verify_cpu_s_today"] == {"used": 12.5, "limit": 14400.0}
    assert limits["results_bytes"]["limit"] == 2_000_000_000 and 0 < limits["results_bytes"]["used"] < 10_000
    alice, _ = sign_in(portal, "alice")
    page = alice.get("/submit").text
    assert "1 of 25 jobs not yet finished" in page and "12 of 14400 CPU s" in page
    with portal.client("op1") as c:
        assert c.get("/api/me").json()["limits"]["unfinished_jobs"]["limit"] is None
