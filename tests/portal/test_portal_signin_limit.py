"""Sign-in rate limit on real uvicorn: keyed on the real client address, and never refusing a right token.

Six wrong sign-ins followed by a right one: the right one works (API and sign-in page). A client cannot pick its
own key with ``X-Forwarded-For`` unless the server was told to trust the proxy it comes through
(``swarmdeck server --trust-proxy ADDR``); then the proxy's word is the client's address."""
import httpx
import pytest
from portal_fixtures import CSRF, make_portal

from swarmdeck.console.portal.app import HttpSettings


def test_six_wrong_sign_ins_then_a_right_one_signs_in(portal):
    with portal.client(None) as c:
        codes = [c.post("/api/session", json={"token": "sdk_wrong"}).status_code for _ in range(6)]
        assert codes == [401] * 5 + [429]
        r = c.post("/api/session", json={"token": portal.tokens["alice"]})
        assert r.status_code == 200 and r.json()["user"]["name"] == "alice"
        assert c.get("/api/me").json()["name"] == "alice"
        r = c.post("/api/session", json={"token": "sdk_wrong"})  # wrong ones are still limited
        assert r.status_code == 429 and "the limit is 5" in r.json()["error"]


def test_the_sign_in_page_takes_a_right_token_after_six_wrong_ones(portal):
    c = httpx.Client(base_url=portal.url, timeout=30)
    codes = []
    for token in ["sdk_wrong"] * 6 + [portal.tokens["bob"]]:
        nonce = CSRF.search(c.get("/signin").text).group(1)
        codes.append(c.post("/signin", data={"csrf": nonce, "token": token}).status_code)
    assert codes == [401] * 5 + [429] + [303]
    assert "My jobs" in c.get("/jobs").text
    c.close()


def test_failures_stop_being_stored_at_the_limit(portal):
    with portal.client(None) as c:
        for _ in range(30):
            c.post("/api/session", json={"token": "sdk_wrong"})
    assert portal.service.db.query_one("SELECT COUNT(*) FROM signin_failures")[0] == 5


def test_x_forwarded_for_is_ignored_by_default(portal):
    with portal.client(None) as c:
        codes = [c.post("/api/session", json={"token": "sdk_wrong"},
                        headers={"X-Forwarded-For": f"203.0.113.{k}"}).status_code for k in range(6)]
    assert codes == [401] * 5 + [429]  # every attempt counted against the real peer, 127.0.0.1
    clients = {r[0] for r in portal.service.db.query("SELECT client FROM signin_failures")}
    assert clients == {"127.0.0.1"}


@pytest.fixture
def behind_proxy(tmp_path):
    p = make_portal(tmp_path, http=HttpSettings(trust_proxy=("127.0.0.1",)), fleet=6, max_duration=60.0,
                    max_upload_bytes=64 << 10)
    try:
        yield p
    finally:
        p.server.stop()
        p.service.close()


def test_a_trusted_proxys_forwarded_address_is_the_key(behind_proxy):
    with behind_proxy.client(None) as c:
        one = {"X-Forwarded-For": "203.0.113.1"}
        codes = [c.post("/api/session", json={"token": "sdk_wrong"}, headers=one).status_code for _ in range(6)]
        assert codes == [401] * 5 + [429]
        r = c.post("/api/session", json={"token": "sdk_wrong"}, headers={"X-Forwarded-For": "203.0.113.2"})
        assert r.status_code == 401  # another client behind the same proxy has its own count
        r = c.post("/api/session", json={"token": behind_proxy.tokens["alice"]}, headers=one)
        assert r.status_code == 200
    clients = {r[0] for r in behind_proxy.service.db.query("SELECT client FROM signin_failures")}
    assert clients == {"203.0.113.1", "203.0.113.2"}
