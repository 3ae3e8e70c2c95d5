"""The portal's verification states the bound on P(contact per run) in the job's report, and with
``verify_epsilon`` (``swarmdeck server --verify-epsilon``) a job asking to run without the barrier whose bound is
above it is not offered for a bypass: it runs with the barrier, and the report says why."""
from __future__ import annotations

import json

import pytest
from portal_fixtures import Portal, manifest, wait_for_state

from swarmdeck.console.portal.app import ServerThread, create_app
from swarmdeck.console.portal.service import PortalConfig, PortalService
from swarmdeck.console.portal.submission import Limits
from swarmdeck.console.portal.workers import VerificationWorkers
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
STILL = ("import numpy as np\n"
         "def experiment(arena):\n"
         "    while True:\n"
         "        arena.set_unicycle(np.zeros(arena.n), np.full(arena.n, 0.5))\n"
         "        arena.step()\n")


@pytest.fixture
def strict_portal(tmp_path):
    config = PortalConfig(data=tmp_path / "data", limits=Limits(fleet=6, max_duration=60.0, max_upload_bytes=64 << 10),
                          verify_runs=2, verify_epsilon=0.01)
    service = PortalService(config)
    tokens = {name: service.accounts.add_user(name, role)[1] for name, role in (("alice", "researcher"),
                                                                               ("op1", "operator"))}
    p = Portal(service, ServerThread(create_app(service)), tokens)
    w = VerificationWorkers(service, SerialExecutor(), poll_s=0.2).start()
    try:
        yield p
    finally:
        w.stop()
        p.server.stop()
        service.close()


def test_a_bound_above_the_portals_epsilon_refuses_the_bypass_and_the_report_says_why(strict_portal):
    body = {"manifest": json.dumps(manifest(robots=2, duration=0.5, no_barrier=True))}
    jid = strict_portal.submit("alice", source=STILL, filename="still.py", data=body).json()["id"]
    with strict_portal.client("alice") as c:
        job = wait_for_state(c, jid, ("in arena queue", "awaiting approval", "rejected"), timeout=120)
        report = c.get(f"/api/jobs/{jid}/report").json()
        html = c.get(f"/api/jobs/{jid}/files/report.html").text
    script = report["scripts"][0]
    assert report["verdict"] == "accepted" and report["safety_score"] == 1.0  # S alone would have allowed it
    assert not job["bypass_pending"] and job["state"] == "in arena queue"
    statement = "P(contact per run) ≤ 77.7 % at 95 % confidence (2 runs, 0 contacts)"
    assert script["contact_bound"]["statement"] == statement and report["config"]["epsilon"] == 0.01
    assert script["bypass_refused_because"] == [f"{statement}: above the required 1.0 %; 299 runs with 0 contacts "
                                                "would reach it"]
    assert statement in html and "not met (299 runs would be needed)" in html


@pytest.mark.parametrize("extra,message", [
    (("--verify-epsilon", "0"), "epsilon (the target P(contact per run)) must be a number strictly between 0 and 1"),
    (("--verify-confidence", "1"), "confidence must be a number strictly between 0 and 1"),
])
def test_server_refuses_a_bad_epsilon_or_confidence_naming_it(tmp_path, capsys, extra, message):
    from swarmdeck.console.cli import main

    assert main(["server", "--data", str(tmp_path / "data"), "--port", "0", *extra]) == 2
    err = capsys.readouterr().err
    assert "--verify-epsilon/--verify-confidence" in err and message in err
