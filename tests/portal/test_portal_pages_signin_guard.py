"""Every page behind sign-in goes through the one session dependency: without a session (none, a made-up one, or
one signed out) each sends the browser to /signin (303) and does nothing; the live stream answers 401."""
import re

from fastapi.routing import APIRoute
from portal_fixtures import sign_in

from swarmdeck.console.portal import pages
from swarmdeck.console.portal.livefeed import LiveFeed

OPEN = {"/signin", "/static/{name}", "/docs", "/docs/assets/{name}", "/openapi.json", "/jobs/{job_id}/live"}


def _pages(service) -> list[APIRoute]:
    """The page routes (:func:`swarmdeck.console.portal.pages.router`) but sign-in, static files and the stream."""
    return [r for r in pages.router(service, LiveFeed()).routes if isinstance(r, APIRoute) and r.path not in OPEN]


def _depends_on(route: APIRoute, name: str) -> bool:
    stack = list(route.dependant.dependencies)
    while stack:
        d = stack.pop()
        if getattr(d.call, "__name__", "") == name:
            return True
        stack.extend(d.dependencies)
    return False


def test_every_page_behind_sign_in_uses_the_session_dependency(portal):  # noqa: F811
    routes = _pages(portal.service)
    assert len(routes) >= 16
    assert [r.path for r in routes if not _depends_on(r, "signed_in")] == []


def test_without_a_session_every_page_goes_to_sign_in_and_changes_nothing(portal):  # noqa: F811
    jid = portal.submit("alice").json()["id"]
    alice, csrf = sign_in(portal, "alice")
    alice.post("/signout", data={"csrf": csrf})
    cookies = ({}, {"swarmdeck_session": "made-up"}, dict(alice.cookies))
    routes = _pages(portal.service)
    assert len(routes) >= 16
    for jar in cookies:
        with portal.client(None) as c:
            c.cookies.update(jar)
            for route in routes:
                path = re.sub(r"\{job_id\}", str(jid), route.path).replace("{name}", "run.json")
                path = path.replace("{action}", "cancel")
                for method in route.methods:
                    r = c.request(method, path, data={"csrf": csrf} if method == "POST" else None)
                    assert r.status_code == 303 and r.headers["location"] == "/signin", (method, path, r.status_code)
            assert c.get(f"/jobs/{jid}/live").status_code == 401
    assert portal.service.job_state(jid) == "awaiting verification"
    assert not portal.service.arena_stopped
