"""A verification error reads as the researcher needs it (issue 26 item 13): once (not once per run), with the
file name they uploaded (not the stored `script.py` nor the sandbox's random folder), the line and an excerpt of
their code; a syntax error is found by compiling, before any sandbox run; the report draws no empty chart; a
rejected job shows no safety score; `swarmdeck jobs` does not cut a message mid-word."""
from __future__ import annotations

import re

import pytest
from portal_fixtures import make_portal, sign_in, wait_for_state

from swarmdeck.console.cli._client import job_line
from swarmdeck.console.portal.workers import VerificationWorkers
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor

BAD = "import numpy as np\ndef experiment(arena):\n    x = = 1\n"
CRASH = "def experiment(arena):\n    arena.step()\n    raise KeyError('oops')\n"


@pytest.fixture
def portal3(tmp_path):
    p = make_portal(tmp_path, fleet=6, max_duration=60.0, max_upload_bytes=64 << 10, verify_runs=3)
    w = VerificationWorkers(p.service, SerialExecutor(), poll_s=0.2).start()
    try:
        yield p
    finally:
        w.stop()
        p.server.stop()
        p.service.close()


def test_a_syntax_error_is_found_by_compiling_and_named_once_with_the_users_file_and_line(portal3):
    jid = portal3.submit("alice", source=BAD, filename="my_walk.py", duration=0.5).json()["id"]
    with portal3.client("alice") as c:
        job = wait_for_state(c, jid, ("rejected",), timeout=60)
        report = c.get(f"/api/jobs/{jid}/report").json()
        html = c.get(f"/api/jobs/{jid}/files/report.html").text
    reason = job["reason"]
    assert reason.startswith("syntax error in my_walk.py at line 3: invalid syntax — x = = 1"), reason
    assert "script.py" not in reason and "swarmdeck-script-" not in reason and "/tmp" not in reason
    assert report["scripts"][0]["runs"] == []  # no sandbox run was spent on it
    cpu = portal3.service.db.query_one("SELECT cpu_s FROM verification_usage WHERE job_id = ?", (jid,))["cpu_s"]
    assert cpu == 0.0
    assert "<svg" not in html and "nothing was run" in html  # no empty chart: it says why there is none
    assert job["safety_score"] is None
    op, _ = sign_in(portal3, "alice")
    try:
        page = op.get(f"/jobs/{jid}").text
    finally:
        op.close()
    assert "safety score S" not in page and "my_walk.py" in page


@pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
def test_a_runtime_error_is_reported_once_for_all_runs_with_the_line_of_code(portal3):
    jid = portal3.submit("alice", source=CRASH, filename="crash_test.py", duration=0.5).json()["id"]
    with portal3.client("alice") as c:
        job = wait_for_state(c, jid, ("rejected",), timeout=120)
        html = c.get(f"/api/jobs/{jid}/files/report.html").text
    reason = job["reason"]
    assert reason.count("KeyError: 'oops'") == 1, reason  # one message, not one per run
    assert "crash_test.py:3" in reason and "raise KeyError('oops')" in reason and "(runs 0, 1, 2)" in reason
    assert "script.py" not in reason and "swarmdeck-script-" not in reason
    assert "swarmdeck-script-" not in html and "S = 0.0000" not in html
    assert job["safety_score"] is None


def test_swarmdeck_jobs_shortens_a_long_reason_at_a_word():
    words = " ".join(f"word{k}" for k in range(80))
    line = job_line({"id": 3, "state": "rejected", "name": "x", "robots": 2, "duration": 1.0, "reason": words})
    tail = line.split("  ")[-1]
    assert tail.endswith("…") and len(tail) <= 200
    assert re.fullmatch(r"(word\d+ )*word\d+…", tail), tail  # every word whole
