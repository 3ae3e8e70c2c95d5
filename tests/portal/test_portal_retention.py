"""The retention policy (``swarmdeck server --retain-days D``): the files of jobs that ended more than D days ago are
deleted by a periodic sweep; the job's row stays with a note (API, page), its downloads say why they are gone; jobs
that have not ended, ended recently or whose exports are still being written are left alone."""
import time

import pytest
from portal_fixtures import make_portal, sign_in

from swarmdeck.console.portal.retention import RetentionSweeper

DAY = 86400.0


@pytest.fixture
def lab(tmp_path):
    p = make_portal(tmp_path, retain_days=30, fleet=6, max_duration=60.0, max_upload_bytes=64 << 10)
    try:
        yield p
    finally:
        p.server.stop()
        p.service.close()


def ended(portal, job_id: int, days_ago: float, state: str = "done", exports: str | None = "ready") -> None:
    """Make a submitted job look as if it ran and ended ``days_ago`` days ago, with its results on disk."""
    folder = portal.service.job_dir(job_id)
    (folder / "recording.mcap").write_bytes(b"\0" * 1000)
    (folder / "run.json").write_text('{"ended_by": "script"}')
    with portal.service.db.transaction() as tx:
        tx.execute("UPDATE jobs SET state = ?, ended = ?, exports = ? WHERE id = ?",
                   (state, time.time() - days_ago * DAY, exports, job_id))


def test_old_results_are_deleted_and_the_job_says_so(lab):
    old, recent, writing, running = (lab.submit("alice", name=n).json()["id"] for n in ("old", "recent", "w", "r"))
    ended(lab, old, 31)
    ended(lab, recent, 29)
    ended(lab, writing, 40, state="failed", exports="writing")
    with lab.service.db.transaction() as tx:
        tx.execute("UPDATE jobs SET created = ? WHERE id = ?", (time.time() - 90 * DAY, running))  # old but queued
    assert lab.service.sweep_results() == [old]
    assert not lab.service.job_dir(old).exists()
    for kept in (recent, writing, running):
        assert (lab.service.job_dir(kept) / "manifest.json").is_file()
    assert lab.service.sweep_results() == []  # once
    with lab.client("alice") as c:
        job = c.get(f"/api/jobs/{old}").json()
        assert job["state"] == "done" and job["results_deleted"] == pytest.approx(time.time(), abs=60)
        assert c.get(f"/api/jobs/{old}/files").json() == []
        r = c.get(f"/api/jobs/{old}/files/recording.mcap")
        assert r.status_code == 404 and "results were deleted on" in r.json()["error"]
        assert "the lab keeps results 30 days" in r.json()["error"]
        assert c.get(f"/api/jobs/{old}/report").status_code == 404
        assert c.get(f"/api/jobs/{recent}/files/recording.mcap").status_code == 200
    alice, _ = sign_in(lab, "alice")
    page = alice.get(f"/jobs/{old}")
    assert page.status_code == 200 and "were deleted on" in page.text and "retention policy" in page.text


def test_the_sweeper_thread_sweeps_at_start_and_then_periodically(lab):
    first, second = (lab.submit("alice", name=n).json()["id"] for n in ("a", "b"))
    ended(lab, first, 45)
    sweeper = RetentionSweeper(lab.service, period_s=0.05).start()
    try:
        deadline = time.monotonic() + 30
        while first not in sweeper.swept and time.monotonic() < deadline:
            time.sleep(0.02)
        ended(lab, second, 45)
        while second not in sweeper.swept and time.monotonic() < deadline:
            time.sleep(0.02)
    finally:
        sweeper.stop()
    assert sweeper.swept == [first, second] and sweeper.errors == 0


def test_without_a_retention_policy_nothing_is_deleted(tmp_path):
    p = make_portal(tmp_path, fleet=6, max_duration=60.0, max_upload_bytes=64 << 10)
    try:
        jid = p.submit("alice").json()["id"]
        ended(p, jid, 3650)
        assert p.service.sweep_results() == [] and (p.service.job_dir(jid) / "recording.mcap").is_file()
    finally:
        p.server.stop()
        p.service.close()
