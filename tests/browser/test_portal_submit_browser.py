"""The Submit page in a real browser (Debian's chromium, Playwright, real uvicorn on loopback; issue 26 item 15): a
refused submission shows every mistake and keeps the chosen file chosen, so fixing one field and sending again
submits; the entry field for archives exists."""
from __future__ import annotations

import os

import pytest
from portal_fixtures import SPIN, browser_sign_in

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-background-networking", "--disable-component-update"]
pytestmark = [pytest.mark.browser, pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium")]


@pytest.fixture
def page(portal):  # noqa: F811
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            p = b.new_page(viewport={"width": 1200, "height": 900})
            browser_sign_in(p, portal, "alice")
            yield p
        finally:
            b.close()


def test_a_refused_form_keeps_the_chosen_file_and_shows_every_mistake(portal, page, tmp_path):  # noqa: F811
    script = tmp_path / "my_walk.py"
    script.write_text(SPIN)
    page.goto(f"{portal.url}/submit")
    assert page.locator("#entry").count() == 1
    page.set_input_files("#script", str(script))
    page.fill("#name", "walk")
    page.fill("#robots", "99")
    page.fill("#duration", "-1")
    page.fill("#initial_poses", "0 0 0\n0.1 0 0")
    page.click("#submit-form button[type=submit]")
    page.wait_for_selector("#form-errors")
    fields = page.eval_on_selector_all("#form-errors li", "els => els.map(e => e.dataset.field)")
    assert sorted(fields) == ["duration", "initial_poses", "robots"]
    assert "poses 1 (0.000, 0.000) and 2" in page.inner_text("#form-errors")
    assert page.eval_on_selector("#script", "el => el.files.length && el.files[0].name") == "my_walk.py"
    assert page.eval_on_selector("#robots", "el => el.classList.contains('bad')")
    page.fill("#robots", "2")
    page.fill("#duration", "1")
    page.fill("#initial_poses", "")
    page.click("#submit-form button[type=submit]")  # the same file, still chosen: no need to pick it again
    page.wait_for_url("**/jobs/*")
    with portal.client("alice") as c:
        jobs = c.get("/api/jobs").json()
    assert len(jobs) == 1 and jobs[0]["script"] == "my_walk.py" and jobs[0]["robots"] == 2
