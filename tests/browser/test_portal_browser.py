"""The portal in a real browser (Debian's chromium, Playwright) against real uvicorn on loopback, with the
verification workers and the arena runner (simulated arena, real time): a researcher signs in, uploads, sees the
verdict, watches the live view move and downloads the recording; an operator approves a job (manual approval)
and stops the arena with the emergency stop; a form posted without its CSRF token is refused.
Screenshots are kept in ``test-artifacts/portal-*.png``."""
from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from mqtt_broker import wait_until
from portal_fixtures import SPIN, browser_sign_in, make_portal, wait_for_state

from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.portal.workers import VerificationWorkers
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import LocalPoolExecutor

CHROMIUM = "/usr/bin/chromium"
ARTIFACTS = Path(__file__).resolve().parents[2] / "test-artifacts"
ARGS = ["--no-sandbox", "--disable-background-networking", "--disable-component-update"]
pytestmark = [pytest.mark.browser,
              pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium"),
              pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")]


@pytest.fixture
def lab(tmp_path):
    """A portal with its verification worker and arena runner, as `swarmdeck server` wires them."""
    portal = make_portal(tmp_path, fleet=6, max_duration=60.0, max_upload_bytes=64 << 10)
    live = portal.server.server.config.app.state.live
    runner = ArenaRunner(portal.service, ArenaSettings(fleet=6, seed=4), live, poll_s=0.2)
    portal.service.arena = runner
    executor = LocalPoolExecutor(1)
    workers = VerificationWorkers(portal.service, executor, poll_s=0.2)
    runner.start()
    workers.start()
    try:
        yield portal
    finally:
        workers.stop()
        runner.stop()
        portal.server.stop()
        portal.service.close()


@pytest.fixture
def browser():
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            yield b
        finally:
            b.close()


def signed_in(browser, portal, who):
    page = browser.new_page(viewport={"width": 1200, "height": 900}, accept_downloads=True)
    browser_sign_in(page, portal, who)
    return page


def test_a_researcher_uploads_sees_the_verdict_watches_it_run_and_downloads_the_recording(lab, browser, tmp_path):
    ARTIFACTS.mkdir(exist_ok=True)
    script = tmp_path / "spin.py"
    script.write_text(SPIN)
    page = signed_in(browser, lab, "alice")
    page.goto(f"{lab.url}/submit")
    page.set_input_files("#script", str(script))
    page.fill("#name", "spin in place")
    page.fill("#robots", "3")
    page.fill("#duration", "6")
    page.click("#submit-form button[type=submit]")
    page.wait_for_url("**/jobs/*")
    jid = int(page.url.rsplit("/", 1)[1])
    page.wait_for_function("() => document.getElementById('verdict').textContent.startsWith('accepted')",
                           timeout=120_000)  # the page reloads itself as the job moves on
    page.wait_for_function("() => window.swarmdeckLive && window.swarmdeckLive.frames > 0", timeout=120_000)
    first = page.evaluate("() => ({tick: swarmdeckLive.tick, poses: swarmdeckLive.poses})")
    assert len(first["poses"]) == 3
    page.wait_for_function("([tick, poses]) => swarmdeckLive.tick > tick && JSON.stringify(swarmdeckLive.poses) !== poses",
                           arg=[first["tick"], json.dumps(first["poses"], separators=(",", ":"))], timeout=60_000)
    later = page.evaluate("() => swarmdeckLive.poses")
    assert later != first["poses"]  # the robots turned (and crept) between two drawn Frames
    page.screenshot(path=str(ARTIFACTS / "portal-live-view.png"))
    page.wait_for_selector("#state:text('done')", timeout=120_000)
    # the exports are written after the run: the page lists them as they appear, then reloads once they are ready
    page.wait_for_selector("#job[data-exports='ready'] ~ ul.files a[data-file='video.mp4']", timeout=180_000)
    page.screenshot(path=str(ARTIFACTS / "portal-job-done.png"), full_page=True)
    with page.expect_download() as dl:
        page.click("a[data-file='recording.mcap']")
    saved = tmp_path / "downloaded.mcap"
    dl.value.save_as(str(saved))
    with open_recording(saved) as rec:
        assert rec.first_frame.n == 3 and rec.count_frames() > 60
    with lab.client("alice") as c:
        assert c.get(f"/api/jobs/{jid}").json()["state"] == "done"


def test_an_operator_approves_and_stops_the_arena_and_a_form_without_csrf_is_refused(lab, browser):
    ARTIFACTS.mkdir(exist_ok=True)
    op = signed_in(browser, lab, "op1")
    op.click("#approval-switch")
    op.wait_for_selector("#approval-mode:text('Manual approval is ON')")
    jid = lab.submit("alice", robots=2, duration=40.0).json()["id"]
    op.wait_for_selector(f"button[data-action=approve][data-job='{jid}']", timeout=120_000)  # verified, waiting for us
    op.screenshot(path=str(ARTIFACTS / "portal-operator-approve.png"), full_page=True)
    op.click(f"button[data-action=approve][data-job='{jid}']")
    with lab.client("alice") as c:
        wait_for_state(c, jid, ("running",))
    # the same e-stop form posted without the session's CSRF token (the browser sends the cookie): refused
    refused = op.request.post(f"{lab.url}/operator/estop", form={"csrf": "forged"}, max_redirects=0)
    assert refused.status == 403 and "CSRF token is missing or wrong" in refused.text()
    assert not lab.service.arena_stopped and lab.service.job_state(jid) == "running"
    errors = []
    op.on("pageerror", lambda exc: errors.append(str(exc)))
    op.goto(f"{lab.url}/operator")
    op.wait_for_selector(f"#arena-state a[href='/jobs/{jid}']")
    # the fleet table: the job's two robots assigned to it, the other four docked; the arena ready
    assert op.locator(f"#fleet td[data-field=state]:text-is('assigned to job {jid}')").count() == 2
    assert op.locator("#fleet td[data-field=state]:text-matches('^(docked|charging)$')").count() == 4
    assert op.inner_text("#fleet-ready").startswith("Arena ready")
    op.click("#estop")
    op.wait_for_selector("#arena-state:text('STOPPED')")
    # stopped where they were: the two robots are away from the chargers (they return on release)
    op.wait_for_function("() => document.querySelectorAll('#fleet td[data-field=state]').length === 6 && "
                         "[...document.querySelectorAll('#fleet td[data-field=state]')]"
                         ".filter((td) => td.textContent === 'away').length === 2", timeout=30_000)
    assert op.inner_text("#fleet-ready").startswith("Arena NOT ready") and not errors, errors
    op.screenshot(path=str(ARTIFACTS / "portal-operator-estop.png"), full_page=True)
    with lab.client("alice") as c:
        job = wait_for_state(c, jid, ("cancelled",))
    assert job["reason"] == "emergency stop by operator op1"
    # the run is over: the runner closed its loop (which stops the robots) and the live feed is empty
    wait_until(lambda: lab.service.arena.current_job is None, timeout=30, what="the run to end")
    assert lab.server.server.config.app.state.live.latest()[1] is None
    assert lab.service.claim_for_arena() is None  # and stays stopped until released
