"""Job ids from outside are validated: an id SQLite cannot hold (``GET /api/jobs/99999999999999999999999``), zero or a
negative one is "no job" (404) on every API route and page that takes one — never a 500."""
import pytest
from portal_fixtures import sign_in

IDS = ("99999999999999999999999", str(2 ** 63), "0", "-1", str(-(2 ** 70)))


@pytest.mark.parametrize("job_id", IDS)
def test_ids_out_of_range_are_404_in_the_api(portal, job_id):
    with portal.client("alice") as c:
        for method, path in (("GET", "/api/jobs/{}"), ("POST", "/api/jobs/{}/cancel"), ("GET", "/api/jobs/{}/report"),
                             ("GET", "/api/jobs/{}/files"), ("GET", "/api/jobs/{}/files/recording.mcap"),
                             ("GET", "/api/jobs/{}/files/video.mp4")):
            r = c.request(method, path.format(job_id))
            assert r.status_code == 404 and r.json() == {"error": f"no job {job_id}", "field": "job"}, (path, r.text)
    with portal.client("op1") as c:
        for action, body in (("approve", None), ("hold", None), ("release", None), ("cancel", None),
                             ("move", {"position": 0}), ("barrier", {"forbid": True})):
            r = c.post(f"/api/operator/jobs/{job_id}/{action}", json=body)
            assert r.status_code == 404 and r.json()["field"] == "job", (action, r.text)
    assert portal.server.thread.alive


@pytest.mark.parametrize("job_id", IDS[:2])
def test_ids_out_of_range_are_not_found_on_the_pages(portal, job_id):
    alice, csrf = sign_in(portal, "alice")
    for path in ("/jobs/{}", "/jobs/{}/report", "/jobs/{}/files/recording.mcap", "/jobs/{}/live"):
        r = alice.get(path.format(job_id))
        assert r.status_code == 404 and f"no job {job_id}" in r.text, (path, r.status_code, r.text[:200])
    r = alice.post(f"/jobs/{job_id}/cancel", data={"csrf": csrf})
    assert r.status_code == 404 and f"no job {job_id}" in r.text
    op, op_csrf = sign_in(portal, "op1")
    r = op.post(f"/operator/jobs/{job_id}/approve", data={"csrf": op_csrf})
    assert r.status_code == 404 and f"no job {job_id}" in r.text
    r = op.post(f"/operator/jobs/{job_id}/up", data={"csrf": op_csrf})
    assert r.status_code == 404


def test_a_job_id_that_is_not_a_number_is_422_naming_it(portal):
    with portal.client("alice") as c:
        r = c.get("/api/jobs/1e5")
        assert r.status_code == 422 and r.json()["field"] == "job_id"
