"""The portal compares two of a researcher's jobs (issue 31 item 4): the metric table and both runs' tracks
(API and page), runs of different arenas said to differ; another researcher's job is 404, as everywhere; a job
with itself, a job not ended, a bad ``with`` are refused with a reason."""
from __future__ import annotations

import time

import pytest
from compare_synth import straight_run
from portal_fixtures import make_portal, sign_in

ENDED = ("verifying", "awaiting approval", "in arena queue", "setting up", "running", "done")


def ended_job(portal, who: str, **run) -> int:  # noqa: F811
    """A job of ``who`` that ran and ended (states moved on directly), with a closed-form recording."""
    r = portal.submit(who)
    assert r.status_code == 201, r.text
    jid = r.json()["id"]
    svc = portal.service
    with svc.db.transaction() as tx:
        for state in ENDED:
            extra = {"verdict": "accepted"} if state == "awaiting approval" else {}
            if state == "done":
                extra["ended"] = time.time()
            svc.db.transition(tx, jid, state, **extra)
    straight_run(svc.job_dir(jid) / "recording.mcap", **run)
    return jid


@pytest.fixture(scope="module")
def portal(tmp_path_factory):  # noqa: F811 - one portal for the module (the tests only read, but for one job)
    p = make_portal(tmp_path_factory.mktemp("compare"), fleet=6, max_duration=60.0, max_upload_bytes=64 << 10)
    try:
        yield p
    finally:
        p.server.stop()
        p.service.close()


@pytest.fixture(scope="module")
def jobs(portal):  # noqa: F811
    a = ended_job(portal, "alice", ticks=33)
    b = ended_job(portal, "alice", ticks=17, n=4, bounds=(-1.2, 1.2, -0.8, 0.8))
    bob = ended_job(portal, "bob", ticks=17)
    return a, b, bob


def test_a_researcher_compares_two_of_her_jobs(portal, jobs):  # noqa: F811
    a, b, _ = jobs
    with portal.client("alice") as c:
        got = c.get(f"/api/jobs/{a}/compare/{b}")
    assert got.status_code == 200, got.text
    body = got.json()
    assert [r["name"] for r in body["runs"]] == [f"job {a}", f"job {b}"]
    assert [r["robots"] for r in body["runs"]] == [3, 4] and [r["contacts"] for r in body["runs"]] == [1, 0]
    assert body["runs"][0]["file"] == "recording.mcap"  # not the lab's folders
    assert f"robots differ: job {a} 3; job {b} 4" in body["differences"]
    t0, t1 = body["tracks"]
    assert len(t0["t"]) == 21 and len(t1["t"]) == 11  # every 0.1 s of 2 s and of 1 s
    assert len(t0["poses"][0]) == 3 and len(t1["poses"][0]) == 4 and t1["bounds"] == [-1.2, 1.2, -0.8, 0.8]
    assert t0["poses"][-1][1][0] == pytest.approx(0.1)  # robot 1 at x = 0.5 − 0.2 × 2 s
    reads = portal.service.run_cache.reads
    with portal.client("alice") as c:
        again = c.get(f"/api/jobs/{b}/compare/{a}").json()  # the other way round: the same runs, not read again
    assert portal.service.run_cache.reads == reads and again["runs"][0]["robots"] == 4


def test_another_researchers_job_is_not_found(portal, jobs):  # noqa: F811
    a, _, bob = jobs
    with portal.client("alice") as c:
        assert c.get(f"/api/jobs/{a}/compare/{bob}").status_code == 404
        assert c.get(f"/api/jobs/{bob}/compare/{a}").status_code == 404
    with portal.client("bob") as c:
        r = c.get(f"/api/jobs/{bob}/compare/{a}")
        assert r.status_code == 404 and r.json()["error"] == f"no job {a}"  # the same answer as for no job at all
    with portal.client("op1") as c:
        assert c.get(f"/api/jobs/{a}/compare/{bob}").status_code == 200  # operators see every job


def test_refusals_say_why(portal, jobs):  # noqa: F811
    a, _, _ = jobs
    waiting = portal.submit("alice").json()["id"]
    with portal.client("alice") as c:
        same = c.get(f"/api/jobs/{a}/compare/{a}")
        assert same.status_code == 422 and "not with itself" in same.json()["error"]
        early = c.get(f"/api/jobs/{a}/compare/{waiting}")
        assert early.status_code == 404 and "can be compared when it has ended" in early.json()["error"]


def test_the_job_page_offers_her_own_ended_jobs_and_shows_the_comparison(portal, jobs):  # noqa: F811
    a, b, bob = jobs
    client, _ = sign_in(portal, "alice")
    try:
        page = client.get(f"/jobs/{a}").text
        assert 'id="compare-form"' in page and f'<option value="{b}">' in page
        assert f'<option value="{bob}">' not in page
        shown = client.get(f"/jobs/{a}/compare", params={"with": b})
        assert shown.status_code == 200
        assert 'id="metrics"' in shown.text and "contacts (onsets)" in shown.text and 'id="compare-tracks"' in shown.text
        assert f"robots differ: job {a} 3; job {b} 4" in shown.text and "/static/compare.js" in shown.text
        assert client.get(f"/jobs/{a}/compare", params={"with": bob}).status_code == 404
        assert client.get(f"/jobs/{a}/compare", params={"with": "x"}).status_code == 422
        assert client.get("/static/compare.js").status_code == 200
    finally:
        client.close()
