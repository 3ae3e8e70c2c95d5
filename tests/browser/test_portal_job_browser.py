"""The job page in a real browser (Debian's chromium, Playwright, real uvicorn on loopback; issue 26 item 17): the
script's output appears while the job runs, and once it has ended the page shows the results in short."""
from __future__ import annotations

import os

import pytest
from mqtt_broker import wait_until
from portal_fixtures import browser_sign_in, skip_verification

from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.sandbox.confinement import probe

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-background-networking", "--disable-component-update"]
CHATTY = ("def experiment(arena):\n"
          "    print('started', flush=True)\n"
          "    k = 0\n"
          "    while True:\n"
          "        arena.step()\n"
          "        k += 1\n"
          "        if k % 30 == 0:\n"
          "            print(f'{k} steps in', flush=True)\n")
pytestmark = [pytest.mark.browser, pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium"),
              pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")]


def test_the_job_page_shows_the_script_output_live_then_the_results(portal):  # noqa: F811
    from playwright.sync_api import sync_playwright

    svc = portal.service
    runner = ArenaRunner(svc, ArenaSettings(fleet=4, seed=2), poll_s=0.1)  # real time
    svc.arena = runner
    runner.start()
    try:
        jid = portal.submit("alice", source=CHATTY, robots=2, duration=8.0).json()["id"]
        skip_verification(portal, jid)
        wait_until(lambda: svc.job_state(jid) == "running", timeout=120, what="the job running")
        with sync_playwright() as pw:
            b = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            try:
                page = b.new_page(viewport={"width": 1200, "height": 1000})
                browser_sign_in(page, portal, "alice")
                page.goto(f"{portal.url}/jobs/{jid}")
                page.wait_for_function("() => document.getElementById('script-log').textContent.includes('60 steps in')",
                                       timeout=60_000)
                assert page.inner_text("#script-log").startswith("started")
                # the page reloads itself when the job ends, and the results appear once run.json is written
                page.wait_for_selector("#state:text('done')", timeout=120_000)
                wait_until(lambda: (svc.job_dir(jid) / "run.json").is_file(), timeout=120, what="run.json")
                page.reload()
                text = page.inner_text("#results")
                assert "The barrier" in text and f"swarmdeck results {jid} -o job{jid}/" in text
            finally:
                b.close()
    finally:
        runner.stop()
