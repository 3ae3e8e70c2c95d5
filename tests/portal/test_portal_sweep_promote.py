"""A sweep may promote its best point to the arena (issue 31.2, ``promote`` / `swarmdeck submit --sweep --promote`):
when the sweep is done, the point with the best mean of the chosen metric (over runs that all finished) becomes a
normal arena job of the same researcher — the sweep's script with that point's values, verified and queued like
any job, pointing back at its sweep; the sweep's reason line names it."""
import json

import pytest
from portal_fixtures import sign_in, wait_for_state

from swarmdeck.console.portal.workers import VerificationWorkers
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor
from swarmdeck.console.sweep.best import objective

SCRIPT = """
import numpy as np
from swarmdeck.devices import params, record_metrics
p = params(gain=1.0)

def experiment(arena):
    record_metrics(score=-(p.gain - 1.0) ** 2)
    while True:
        arena.set_unicycle(np.full(arena.n, 0.01), np.zeros(arena.n))
        arena.step()
"""


@pytest.mark.parametrize("promote,words", [
    ({"goal": "max"}, "the metric must be a name"),
    ({"metric": "score"}, "say whether a lower or a higher score is better"),
    ({"metric": "score", "goal": "best"}, "the goal must be min or max"),
    ({"metric": "min_distance", "by": "mean"}, 'promote must be an object {"metric"'),
    ("min_distance", 'promote must be an object {"metric"'),
])
def test_a_malformed_promote_is_refused_naming_it(portal, promote, words):
    sweep = {"params": ["gain=0.5,1"], "robots": 2, "duration": 1.0, "promote": promote}
    with portal.client("alice") as c:
        r = c.post("/api/sweeps", files={"script": ("g.py", SCRIPT)}, data={"sweep": json.dumps(sweep)})
    assert r.status_code == 422 and r.json()["field"] == "promote" and words in r.json()["error"], r.text


def test_a_built_in_metric_has_its_own_goal_and_a_script_metric_is_its_column():
    assert objective("min_distance").goal == "max" and objective("contacts").goal == "min"
    assert objective("score", "max").column == "metric_score" == objective("metric_score", "max").column


@pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
def test_the_best_point_becomes_an_arena_job_with_its_values(portal):
    sweep = {"name": "gains", "params": ["gain=0.5,1,2"], "robots": 2, "duration": 0.5,
             "promote": {"metric": "score", "goal": "max"}}
    with portal.client("alice") as c:
        r = c.post("/api/sweeps", files={"script": ("g.py", SCRIPT)}, data={"sweep": json.dumps(sweep)})
        assert r.status_code == 201, r.text
        sid = r.json()["id"]
        assert r.json()["sweep"]["promote"] == {"metric": "metric_score", "goal": "max"}
    workers = VerificationWorkers(portal.service, SerialExecutor(), poll_s=0.1).start()
    try:
        with portal.client("alice") as c:
            done = wait_for_state(c, sid, ("done", "failed"), timeout=180)
            assert done["state"] == "done", done
            promoted = [j for j in c.get("/api/jobs").json() if j["origin"] == sid]
    finally:
        workers.stop()
    assert len(promoted) == 1, promoted
    job = promoted[0]
    assert job["params"] == {"gain": 1.0} and job["robots"] == 2 and job["sweep"] is None, job
    assert job["name"] == "gains: best metric_score (max)" and job["owner"] == "alice"
    assert f"promoted to job {job['id']}" in done["reason"] and "gain=1.0" in done["reason"], done["reason"]
    browser, _ = sign_in(portal, "alice")
    try:
        page = browser.get(f"/jobs/{job['id']}").text
        assert 'id="params"' in page and "gain=1.0" in page and f'href="/jobs/{sid}"' in page
    finally:
        browser.close()
    with portal.client("bob") as c:
        assert c.get(f"/api/jobs/{job['id']}").status_code == 404


def test_promoted_values_pass_the_same_check_as_a_submitted_manifest(portal):
    """Before the fix, promote stored whatever values it was handed (a NaN gain became a queued job's parameter)."""
    from swarmdeck.console.portal.errors import BadInput

    sweep = {"params": ["gain=0.5,1"], "robots": 2, "duration": 1.0}
    with portal.client("alice") as c:
        r = c.post("/api/sweeps", files={"script": ("g.py", SCRIPT)}, data={"sweep": json.dumps(sweep)})
        assert r.status_code in (200, 201), r.text
        sid = r.json()["id"]
    alice = portal.service.accounts.user_named("alice")
    job = portal.service.job(alice, sid)
    for bad in ({"gain": float("nan")}, {"not a name": 1.0}, {"gain": [1, 2]}):
        with pytest.raises(BadInput) as err:
            portal.service.promote(job, bad, 2, 1.0, "best")
        assert err.value.field == "params", err.value
    assert [j.id for j in portal.service.jobs(alice)] == [sid]  # nothing was queued
