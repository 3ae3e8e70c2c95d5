"""A contact on the arena is in the job's result: run.json counts the episodes and names the robots, the job's
reason (its page, ``swarmdeck jobs``) says it, the recording holds exactly one event for it and the operator page
alerts. Forced with a bypass the operator approved on an arena whose guard the trusted side disabled
(``ArenaSettings(guard=None)``, a test hook no option reaches)."""
import json

import pytest
from portal_fixtures import sign_in, wait_for_state

from swarmdeck.console.cli._client import job_line
from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.portal.service import BYPASS_VERDICT
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.sandbox.confinement import probe

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

STRAIGHT = """
import numpy as np

def experiment(arena):
    while True:
        arena.set_unicycle(np.full(arena.n, 0.2), np.zeros(arena.n))
        arena.step()
"""


@pytest.fixture
def unguarded(portal):
    runner = ArenaRunner(portal.service, ArenaSettings(fleet=4, seed=3, fast=True, guard=None), poll_s=0.2)
    portal.service.arena = runner
    runner.start()
    yield runner
    runner.stop()


def test_a_contact_is_counted_once_and_named_in_the_result(portal, unguarded):
    svc = portal.service
    jid = portal.submit("alice", source=STRAIGHT, filename="straight.py", duration=2.5, no_barrier=True,
                        initial_poses=[[-0.35, 0.0, 0.0], [0.35, 0.0, 3.141592653589793]]).json()["id"]
    with svc.db.transaction() as tx:  # as verification and an operator's approval of the bypass would
        svc.db.transition(tx, jid, "verifying")
        svc.db.transition(tx, jid, "awaiting approval", verdict=BYPASS_VERDICT, safety_score=1.0)
    with portal.client("op1") as op:
        assert op.post(f"/api/operator/jobs/{jid}/bypass", json={"approve": True}).status_code == 200
    with portal.client("alice") as c:
        job = wait_for_state(c, jid, ("done", "failed"), timeout=120)
    assert job["state"] == "done" and job["bypass"] is True
    assert "1 contact(s) between robots (0–1)" in job["reason"] and "1 contact(s)" in job_line(job)
    run = json.loads((svc.job_dir(jid) / "run.json").read_text())
    assert run["contacts"]["count"] == 1 and run["contacts"]["robots"] == [0, 1]
    assert run["bypass"]["granted"] and run["bypass"]["revoked"] is None
    with open_recording(svc.job_dir(jid) / "recording.mcap") as rec:
        events = [e for _, f in rec.frames() for e in f.events if e.startswith("CONTACT:")]
    assert len(events) == 1 and "robots 0 and 1" in events[0]
    with portal.client("op1") as op:
        alerts = op.get("/api/operator/arena").json()["alerts"]
        assert alerts["job"] == jid and alerts["messages"] == events
    page, _ = sign_in(portal, "op1")
    try:
        html = page.get("/operator").text
        assert 'id="safety-alerts"' in html and "robots 0 and 1 touch" in html
        assert "1 contact(s) between robots" in page.get(f"/jobs/{jid}").text
    finally:
        page.close()
