"""CSRF tokens are derived from the session (HMAC-SHA-256 of the session id under the data folder's secret), not
stored: the database holds no CSRF token, one session's token does not work for another, and a session keeps its
token across a server restart. The pages' forms and the API's X-CSRF-Token keep working (test_portal_pages.py)."""
import httpx
from portal_fixtures import make_portal, sign_in

from swarmdeck.console.portal.app import ServerThread, create_app
from swarmdeck.console.portal.service import PortalService


def test_the_database_holds_no_csrf_token(portal):
    alice, csrf = sign_in(portal, "alice")
    bob, bob_csrf = sign_in(portal, "bob")
    assert csrf != bob_csrf and len(csrf) == 64
    assert "csrf" not in [r["name"] for r in portal.service.db.query("PRAGMA table_info(sessions)")]
    portal.service.db.query("PRAGMA wal_checkpoint(FULL)")
    raw = b"".join(p.read_bytes() for p in portal.service.data.glob("portal.sqlite3*"))
    assert csrf.encode() not in raw and bob_csrf.encode() not in raw
    jid = portal.submit("alice").json()["id"]
    assert alice.post(f"/jobs/{jid}/cancel", data={"csrf": bob_csrf}).status_code == 403  # bob's token: refused
    r = alice.post(f"/api/jobs/{jid}/cancel", headers={"X-CSRF-Token": bob_csrf})
    assert r.status_code == 403 and r.json()["field"] == "X-CSRF-Token"
    assert alice.post(f"/jobs/{jid}/cancel", data={"csrf": csrf}).status_code == 303
    assert portal.service.job_state(jid) == "cancelled"


def test_a_session_keeps_its_csrf_token_across_a_restart(tmp_path):
    first = make_portal(tmp_path, fleet=6, max_duration=60.0, max_upload_bytes=64 << 10)
    alice, csrf = sign_in(first, "alice")
    cookies = dict(alice.cookies)
    config = first.service.config
    first.server.stop()
    first.service.close()
    service = PortalService(config)  # the same data folder, a new process's view of it
    server = ServerThread(create_app(service))
    try:
        with httpx.Client(base_url=server.url, cookies=cookies, timeout=30) as again:
            me = again.get("/api/me").json()
            assert me["name"] == "alice" and me["csrf"] == csrf
    finally:
        server.stop()
        service.close()
