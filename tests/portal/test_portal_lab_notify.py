"""Notifications (issue 30 item 3): a researcher is told when their job is verified, starts, ends or is rejected,
by their webhook and by e-mail through the lab's SMTP server (both on loopback here); a webhook that answers 500
is retried with backoff, one that hangs is cut off, and neither ever blocks the queue."""
import json

from lab_fixtures import make_lab, queued, until

from swarmdeck.console.portal.notify import Notifier, SmtpSettings
from swarmdeck.console.portal.states import JobState


def run_through(svc, job_id, arena="floor"):
    job = svc.claim_for_arena(arena=arena)
    assert job.id == job_id
    svc.mark_running(job_id)
    svc.finish_run(job_id, JobState.DONE, None)


def test_webhook_and_email_hear_of_every_step(tmp_path, hooks, smtp_server):
    lab = make_lab(tmp_path, smtp=SmtpSettings(smtp_server.host, smtp_server.port, sender="arena@lab.example"))
    svc = lab.service
    notifier = Notifier(svc.lab, svc.config.smtp, timeout_s=5.0, backoff_s=0.05, poll_s=0.05).start()
    try:
        with lab.client("alice") as c:
            r = c.put("/api/me/notifications", json={"webhook": hooks.url("/alice"), "email": "alice@lab.example"})
            assert r.status_code == 200 and r.json()["email_configured"] is True
            bad = c.put("/api/me/notifications", json={"webhook": "ftp://x", "email": None})
            assert bad.status_code == 422 and bad.json()["field"] == "webhook"
            assert c.put("/api/me/notifications", json={"email": "not an address"}).json()["field"] == "email"
        ok = lab.submit("alice", robots=2, duration=5.0).json()["id"]
        svc.claim_for_verification()
        svc.finish_verification(ok, "accepted", 0.9, [])
        run_through(svc, ok)
        bad = lab.submit("alice", robots=2, duration=5.0).json()["id"]
        svc.claim_for_verification()
        svc.finish_verification(bad, "rejected", None, ["it drives into the wall"])
        expected = [(ok, "verified"), (ok, "started"), (ok, "ended"), (bad, "rejected")]
        got = until(lambda: len(hooks.bodies.get("/alice", [])) == 4 and hooks.bodies["/alice"], what="webhooks")
        assert [(b["job"], b["event"]) for b in got] == expected
        assert got[2]["state"] == "done" and got[2]["arena"] == "floor" and got[3]["state"] == "rejected"
        mails = until(lambda: len(smtp_server.messages) == 4 and smtp_server.messages, what="e-mails")
        assert [m["X-Rcpt"] for m in mails] == ["alice@lab.example"] * 4
        assert mails[0]["From"] == "arena@lab.example"
        assert mails[2]["Subject"] == f'swarmdeck: job {ok} "spin" ended (done)'
        assert "it drives into the wall" in mails[3].get_payload()
        # bob set nothing: nothing is sent for his jobs
        queued(lab, "bob", robots=2, duration=5.0)
        with lab.client("alice") as c:
            sent = c.get("/api/me/notifications").json()["sent"]
        assert len(sent) == 8 and all(s["sent"] is not None for s in sent)
    finally:
        notifier.stop()
        lab.server.stop()
        svc.close()


def test_a_failing_or_hanging_webhook_is_retried_and_never_blocks_the_queue(tmp_path, hooks):
    lab = make_lab(tmp_path)
    svc = lab.service
    hooks.fail["/alice"] = 2  # two 500s, then it works
    hooks.hang.add("/bob")  # never answers
    svc.lab.set_targets(svc.accounts.user_named("alice").id, hooks.url("/alice"), None)
    svc.lab.set_targets(svc.accounts.user_named("bob").id, hooks.url("/bob"), None)
    notifier = Notifier(svc.lab, None, timeout_s=0.5, backoff_s=0.05, max_attempts=3, poll_s=0.05).start()
    try:
        b = queued(lab, "bob", robots=2, duration=5.0)
        a = queued(lab, "alice", robots=2, duration=5.0)
        run_through(svc, b)  # bob's webhook hangs meanwhile: the queue does not wait for it
        run_through(svc, a)
        assert svc.job_state(a) == JobState.DONE and svc.job_state(b) == JobState.DONE
        got = until(lambda: len(hooks.bodies.get("/alice", [])) == 2 and hooks.bodies["/alice"], what="retries")
        assert [x["event"] for x in got] == ["started", "ended"]
        assert hooks.tries["/alice"] == 4  # two 500s (retried), then the two events
        gave_up = until(lambda: [n for n in svc.lab.notices() if n["gave_up"]], timeout=60, what="giving up")
        assert {n["job_id"] for n in gave_up} == {b} and all(n["attempts"] == 3 for n in gave_up)
        assert all("timed out" in n["error"] or "Timeout" in n["error"] for n in gave_up), gave_up
    finally:
        notifier.stop()
        lab.server.stop()
        svc.close()


def test_the_webhook_body_is_the_documented_json(tmp_path, hooks):
    lab = make_lab(tmp_path)
    svc = lab.service
    svc.lab.set_targets(svc.accounts.user_named("carol").id, hooks.url("/c"), None)
    job = queued(lab, "carol", robots=2, duration=5.0)
    with lab.client("op1") as op:
        assert op.post(f"/api/operator/jobs/{job}/cancel").status_code == 200
    notifier = Notifier(svc.lab, None, poll_s=0.05)
    try:
        assert notifier.send_due() == 1
    finally:
        lab.server.stop()
        svc.close()
    body = hooks.bodies["/c"][0]
    assert set(body) == {"event", "job", "name", "owner", "state", "reason", "arena", "time"}
    assert body["event"] == "ended" and body["state"] == "cancelled" and json.dumps(body)
