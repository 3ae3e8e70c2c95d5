"""Auth boundaries of the portal's API on real uvicorn: every request authenticated, a disabled token refused
mid-session, another user's job is 404, operator endpoints refused to researchers, cookie sessions with CSRF,
sign-in rate limiting, tokens stored only hashed."""
import httpx

from swarmdeck.console.portal.api import SESSION_COOKIE


def test_requests_without_a_valid_token_are_401_naming_the_header(portal):
    with portal.client(None) as c:
        assert c.get("/api/health").json() == {"ok": True}  # liveness needs no account
        for headers in ({}, {"Authorization": "Basic abc"}, {"Authorization": "Bearer sdk_not-a-real-token"},
                        {"Authorization": "Bearer " + "x" * 50}):
            r = c.get("/api/jobs", headers=headers)
            assert r.status_code == 401 and r.json()["field"] == "Authorization", r.text
        r = c.post("/api/jobs", files={"script": ("a.py", b"x = 1\n")}, data={"manifest": "{}"})
        assert r.status_code == 401
    assert portal.service.db.query("SELECT * FROM jobs") == []


def test_a_token_disabled_mid_session_is_refused_from_its_next_request(portal):
    with portal.client("alice") as c:
        assert c.get("/api/me").json()["name"] == "alice"
        job = portal.submit("alice").json()
        portal.service.accounts.disable("alice")  # what `swarmdeck users disable alice` does
        r = c.get(f"/api/jobs/{job['id']}")
        assert r.status_code == 401 and r.json() == {"error": "the account 'alice' is disabled",
                                                     "field": "Authorization"}
        assert portal.submit("alice").status_code == 401


def test_another_researchers_job_is_404_everywhere(portal):
    job = portal.submit("bob").json()
    jid = job["id"]
    with portal.client("alice") as c:
        for method, path in (("GET", f"/api/jobs/{jid}"), ("POST", f"/api/jobs/{jid}/cancel"),
                             ("GET", f"/api/jobs/{jid}/report"), ("GET", f"/api/jobs/{jid}/files"),
                             ("GET", f"/api/jobs/{jid}/files/manifest.json"), ("GET", "/api/jobs/99999")):
            r = c.request(method, path)
            assert r.status_code == 404 and r.json() == {"error": f"no job {jid if '99999' not in path else 99999}",
                                                         "field": "job"}, (path, r.text)
        assert c.get("/api/jobs").json() == []
    with portal.client("bob") as c:
        assert [j["id"] for j in c.get("/api/jobs").json()] == [jid]
        assert c.get(f"/api/jobs/{jid}/files/manifest.json").json()["robots"] == 2
        assert c.get(f"/api/jobs/{jid}/files/..%2Fportal.sqlite3").status_code == 404
    assert portal.service.job_state(jid) == "awaiting verification"


def test_researchers_cannot_use_operator_endpoints(portal):
    jid = portal.submit("alice").json()["id"]
    with portal.client("alice") as c:
        for method, path, body in (("POST", f"/api/operator/jobs/{jid}/hold", None),
                                   ("POST", f"/api/operator/jobs/{jid}/approve", None),
                                   ("POST", f"/api/operator/jobs/{jid}/move", {"position": 0}),
                                   ("POST", "/api/operator/estop", None), ("POST", "/api/operator/release", None),
                                   ("PUT", "/api/operator/settings", {"manual_approval": True}),
                                   ("GET", "/api/operator/settings", None), ("GET", "/api/operator/audit", None),
                                   ("GET", "/api/operator/arena", None), ("GET", "/api/operator/stats", None)):
            r = c.request(method, path, json=body)
            assert r.status_code == 403 and r.json()["field"] == "Authorization", (path, r.text)
    assert portal.service.job_state(jid) == "awaiting verification" and not portal.service.arena_stopped
    assert not portal.service.manual_approval
    with portal.client("op1") as c:
        assert [j["id"] for j in c.get("/api/jobs").json()] == [jid]  # operators see everyone's jobs
        assert c.post(f"/api/operator/jobs/{jid}/hold").json()["state"] == "held"
        log = c.get("/api/operator/audit").json()
        assert [(e["user"], e["action"], e["job"]) for e in log] == [("op1", "hold", jid)]
        stats = c.get("/api/operator/stats").json()["rejected"]
        assert stats["by_status"]["403"] == 10


def test_cookie_sessions_need_the_csrf_token_for_changes(portal):
    with portal.client(None) as c:
        r = c.post("/api/session", json={"token": portal.tokens["alice"]})
        assert r.status_code == 200
        cookie = r.headers["set-cookie"]
        assert "HttpOnly" in cookie and "SameSite=strict" in cookie
        csrf = r.json()["csrf"]
        assert c.get("/api/me").json()["name"] == "alice"  # the cookie alone signs reads in
        jid = portal.submit("alice").json()["id"]
        r = c.post(f"/api/jobs/{jid}/cancel")
        assert r.status_code == 403 and r.json()["field"] == "X-CSRF-Token"
        r = c.post(f"/api/jobs/{jid}/cancel", headers={"X-CSRF-Token": csrf})
        assert r.status_code == 200 and r.json()["state"] == "cancelled"
        portal.service.accounts.disable("alice")
        assert c.get("/api/me").status_code == 401
        c.delete("/api/session")
        assert SESSION_COOKIE not in c.cookies


def test_sign_in_is_rate_limited_per_address(portal):
    with portal.client(None) as c:
        codes = [c.post("/api/session", json={"token": "sdk_wrong"}).status_code for _ in range(6)]
        assert codes == [401] * 5 + [429]  # a right token still works: test_portal_signin_limit.py


def test_the_database_holds_no_token_in_clear(portal):
    raw = b"".join(p.read_bytes() for p in (portal.service.data).glob("portal.sqlite3*"))
    assert raw and not any(t.encode() in raw for t in portal.tokens.values())
    with httpx.Client(base_url=portal.url) as c:  # and the tokens work
        assert c.get("/api/me", headers={"Authorization": f"Bearer {portal.tokens['op2']}"}).json()["role"] == "operator"


def test_the_openapi_page_documents_the_api(portal):
    with portal.client(None) as c:
        assert c.get("/docs").status_code == 200
        spec = c.get("/openapi.json").json()
    assert {"/api/jobs", "/api/jobs/{job_id}", "/api/operator/estop"} <= set(spec["paths"])
    upload = spec["paths"]["/api/jobs"]["post"]["requestBody"]["content"]["multipart/form-data"]["schema"]
    assert set(upload["properties"]) == {"script", "manifest", "entry"}
