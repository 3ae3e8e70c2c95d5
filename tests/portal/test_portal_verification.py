"""Verification workers behind the API: a script that fails verification is rejected with the reason and its
report; a good one is approved and queued for the arena at once, or waits for an operator under manual approval."""
import pytest
from portal_fixtures import CRASH, SPIN, wait_for_state

from swarmdeck.console.portal.workers import VerificationWorkers
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")


@pytest.fixture
def workers(portal):
    w = VerificationWorkers(portal.service, SerialExecutor(), poll_s=0.2).start()
    yield w
    w.stop()


def test_a_script_that_fails_verification_is_rejected_with_the_reason(portal, workers):
    jid = portal.submit("alice", source=CRASH, filename="crash.py", duration=0.5).json()["id"]
    with portal.client("alice") as c:
        job = wait_for_state(c, jid, ("rejected",), timeout=60)
        assert job["verdict"] == "rejected" and "KeyError: 'oops'" in job["reason"]
        report = c.get(f"/api/jobs/{jid}/report").json()
        assert report["schema"] == "swarmdeck.verification/1" and report["verdict"] == "rejected"
        names = {f["name"] for f in c.get(f"/api/jobs/{jid}/files").json()}
        assert {"report.json", "report.html", "manifest.json"} <= names
        assert c.post(f"/api/jobs/{jid}/cancel").status_code == 409  # it has ended


def test_verified_jobs_queue_for_the_arena_unless_an_operator_approves_each(portal, workers):
    svc = portal.service
    first = portal.submit("alice", source=SPIN, duration=0.5).json()["id"]
    with portal.client("alice") as c:
        job = wait_for_state(c, first, ("in arena queue",), timeout=60)
        assert job["verdict"].startswith("accepted") and job["position"] == 0
    with portal.client("op1") as op:
        assert op.put("/api/operator/settings", json={"manual_approval": True}).json() == {"manual_approval": True}
        second = portal.submit("bob", source=SPIN, duration=0.5).json()["id"]
        with portal.client("bob") as c:
            wait_for_state(c, second, ("awaiting approval",), timeout=60)
        arena = op.get("/api/operator/arena").json()
        assert [j["id"] for j in arena["queue"]] == [first] and arena["manual_approval"]
        assert op.post(f"/api/operator/jobs/{second}/approve").json()["state"] == "in arena queue"
        assert op.post(f"/api/operator/jobs/{second}/move", json={"position": 0}).json()["position"] == 0
        assert [j["id"] for j in op.get("/api/operator/arena").json()["queue"]] == [second, first]
        r = op.post(f"/api/operator/jobs/{second}/move", json={"position": -1})
        assert r.status_code == 422 and r.json()["field"] == "position"
    assert svc.db.check() == "ok"


def test_a_multi_file_archive_is_verified_from_its_entry_with_its_modules(portal, workers):
    import io
    import zipfile

    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as z:
        z.writestr("run.py", "from lib.moves import experiment\n")
        z.writestr("lib/__init__.py", "")
        z.writestr("lib/moves.py", SPIN)
    r = portal.submit("alice", source=buf.getvalue(), filename="multi.zip", duration=0.5, entry="run.py")
    assert r.status_code == 201, r.text
    with portal.client("alice") as c:
        job = wait_for_state(c, r.json()["id"], ("in arena queue", "rejected"), timeout=60)
    assert job["state"] == "in arena queue" and job["entry"] == "run.py", job
