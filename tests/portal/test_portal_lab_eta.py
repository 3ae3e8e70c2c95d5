"""Estimated start and end times (issue 30 item 3), checked against the starts the portal's own claims then make
on a simulated queue (virtual time: :mod:`swarmdeck.console.portal.simqueue`): exact when the set-up and return
take what the portal measured, and off by at most the set-up/return jitter of the jobs ahead otherwise."""
import pytest
from lab_fixtures import queued

from swarmdeck.console.portal.simqueue import play

T0 = 1_000_000.0


def warm_up(lab, overhead_s):
    """Two jobs per arena, so the portal has measured each arena's set-up and return."""
    for arena in ("floor", "lab", "floor", "lab"):
        queued(lab, "op1", robots=2, duration=5.0, arena=arena)
    return max(p.ended for p in play(lab.service, T0, lambda job, arena: overhead_s))


def batch(lab):
    specs = [("alice", 6, 40.0, "either"), ("alice", 2, 10.0, "either"), ("alice", 3, 25.0, "physical"),
             ("bob", 2, 60.0, "simulated"), ("bob", 4, 15.0, "either"), ("carol", 2, 30.0, "either"),
             ("alice", 2, 20.0, "either"), ("bob", 8, 35.0, "simulated"), ("carol", 4, 12.0, "physical"),
             ("carol", 2, 45.0, "either"), ("alice", 1, 5.0, "either"), ("bob", 2, 50.0, "either")]
    return [queued(lab, who, robots=n, duration=d, needs=needs) for who, n, d, needs in specs]


@pytest.mark.parametrize("jitter", [0.0, 1.5])
def test_etas_match_the_starts_the_queue_then_makes(lab, jitter):
    svc = lab.service
    t0 = warm_up(lab, 6.0)
    ids = batch(lab)
    order = [j.id for j in svc.store.queue()]
    eta = svc.plan(svc.store.waiting_in_order(), t0)
    assert set(eta) == set(ids)

    def true_overhead(job_id, arena):  # deterministic, in [6 - jitter, 6 + jitter]
        return 6.0 + jitter * (((job_id * 7919) % 13) / 6.0 - 1.0)

    played = {p.job_id: p for p in play(svc, t0, true_overhead)}
    assert set(played) == set(ids)
    for k, job_id in enumerate(order):
        err = abs(played[job_id].started - eta[job_id].start)
        if jitter == 0.0:
            assert err < 1e-6 and played[job_id].arena == eta[job_id].arena
            assert abs(played[job_id].ended - eta[job_id].end) < 1e-6
        else:  # each job ahead can move a start by at most its own jitter
            assert err <= (k + 1) * jitter + 1e-6, (job_id, k, err)
    # and the queue's ETAs are on the API and in `swarmdeck jobs` (not here: the virtual clock is in the past)


def test_the_api_and_swarmdeck_jobs_show_the_estimates(lab):
    import time

    from swarmdeck.console.cli._client import job_line

    first = queued(lab, "alice", robots=6, duration=30.0)
    second = queued(lab, "bob", robots=6, duration=30.0)  # only the floor has 6 robots: after the first
    with lab.client("bob") as c:
        jobs = {j["id"]: j for j in c.get("/api/jobs").json()}
    assert set(jobs) == {second}  # bob sees his own job, with its estimate
    with lab.client("op1") as c:
        everyone = {j["id"]: j for j in c.get("/api/jobs").json()}
    a, b = everyone[first], everyone[second]
    assert a["eta_arena"] == b["eta_arena"] == "floor"
    assert abs(a["eta_start"] - time.time()) < 60 and b["eta_start"] >= a["eta_end"] - 1e-6
    line = job_line(jobs[second])
    assert "starts ~" in line and "on floor" in line and "queue position 2" in line
