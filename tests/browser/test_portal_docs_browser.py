"""/docs in a real browser (Debian's chromium, Playwright) with every request off this machine blocked, as on a lab
network without Internet: Swagger UI renders the portal's API from /openapi.json, nothing else was asked for, and
the page's Content-Security-Policy reported no violation."""
from __future__ import annotations

import os
from urllib.parse import urlsplit

import pytest

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-background-networking", "--disable-component-update"]
pytestmark = [pytest.mark.browser, pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium")]


def test_the_api_page_renders_with_no_network(portal):
    from playwright.sync_api import sync_playwright

    asked, blocked, console = [], [], []
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            page = browser.new_page()

            def route(r):  # noqa: ANN001, ANN202 - only the portal's own origin is reachable
                url = r.request.url
                asked.append(url)
                if urlsplit(url).netloc != urlsplit(portal.url).netloc:
                    blocked.append(url)
                    return r.abort()
                return r.continue_()

            page.route("**/*", route)
            page.on("console", lambda m: console.append(m.text))
            page.goto(portal.url + "/docs")
            page.wait_for_selector(".opblock-summary-path", timeout=30000)
            paths = page.locator(".opblock-summary-path").all_inner_texts()
        finally:
            browser.close()
    assert "/api/jobs" in paths and "/api/operator/estop" in paths
    assert blocked == [] and any(u.endswith("/openapi.json") for u in asked)
    assert not [m for m in console if "Content Security Policy" in m], console
