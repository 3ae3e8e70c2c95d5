"""The verification queue is fair and cannot be stalled (issue 24, item 4): jobs are claimed round-robin across
researchers, so one researcher's stalling jobs — stale tick numbers forever, an Arena of 500 robots when 1 was
declared — each end at once with the reason while another researcher's job is verified between them."""
import textwrap

import pytest
from hostile_scripts import FIVE_HUNDRED, STALE_FOREVER
from portal_fixtures import SPIN, wait_for_state

from swarmdeck.console.portal.workers import VerificationWorkers
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor

confined = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")


def test_claims_go_round_robin_across_researchers(portal):  # noqa: F811
    svc = portal.service
    alice = [portal.submit("alice", duration=0.5).json()["id"] for _ in range(3)]
    bob = [portal.submit("bob", duration=0.5).json()["id"] for _ in range(2)]
    alice.append(portal.submit("alice", duration=0.5).json()["id"])
    order = []
    while (job := svc.claim_for_verification()) is not None:
        order.append(job.id)
    assert order == [alice[0], bob[0], alice[1], bob[1], alice[2], alice[3]]
    assert svc.claim_for_verification() is None


def test_the_turn_goes_on_from_the_researcher_served_last(portal):  # noqa: F811
    svc = portal.service
    first = portal.submit("alice", duration=0.5).json()["id"]
    assert svc.claim_for_verification().id == first
    later = [portal.submit("alice", duration=0.5).json()["id"] for _ in range(2)]
    theirs = portal.submit("bob", duration=0.5).json()["id"]
    assert svc.claim_for_verification().id == theirs  # alice was served last: bob's one job goes first
    assert [svc.claim_for_verification().id for _ in later] == later


@confined
def test_stalling_jobs_end_with_the_reason_and_another_researchers_job_is_verified_between_them(portal):  # noqa: F811
    stallers = [portal.submit("alice", source=textwrap.dedent(src), filename=f"{name}.py", robots=1,
                              duration=2.0).json()["id"]
                for name, src in (("stale", STALE_FOREVER), ("many", FIVE_HUNDRED), ("stale2", STALE_FOREVER))]
    good = portal.submit("bob", source=SPIN, robots=1, duration=0.5).json()["id"]
    workers = VerificationWorkers(portal.service, SerialExecutor(), poll_s=0.2).start()
    try:
        with portal.client("op1") as op:
            jobs = {jid: wait_for_state(op, jid, ("in arena queue", "rejected"), timeout=120)
                    for jid in (*stallers, good)}
    finally:
        workers.stop()
    assert jobs[good]["state"] == "in arena queue" and jobs[good]["verdict"].startswith("accepted")
    stale, many, stale2 = (jobs[j] for j in stallers)
    assert stale["state"] == many["state"] == stale2["state"] == "rejected"
    assert "in 5 ticks in a row (no answer in time, or an answer for another tick" in stale["reason"]
    assert "the script asks for 500 robots but the manifest declares 1" in many["reason"]
    # verified in the order alice, bob, alice, alice: bob's job did not wait behind all of alice's
    assert stale["ended"] <= jobs[good]["updated"] <= many["ended"] <= stale2["ended"]
