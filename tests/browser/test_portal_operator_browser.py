"""The Operator page in a real browser (Debian's chromium, Playwright, real uvicorn on loopback; issue 26 item 16):
the fleet is drawn on the arena and follows /api/operator/arena, and the running job has its own Cancel."""
from __future__ import annotations

import os

import pytest
from mqtt_broker import wait_until
from portal_fixtures import browser_sign_in, skip_verification

from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.sandbox.confinement import probe

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-background-networking", "--disable-component-update"]
SLOW = "def experiment(arena):\n    while True:\n        arena.step()\n"
pytestmark = [pytest.mark.browser, pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium"),
              pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")]


def test_the_operator_sees_the_fleet_on_the_arena_and_cancels_the_running_job(portal):  # noqa: F811
    from playwright.sync_api import sync_playwright

    svc = portal.service
    runner = ArenaRunner(svc, ArenaSettings(fleet=4, seed=2), poll_s=0.1)  # real time: the job runs a while
    svc.arena = runner
    runner.start()
    try:
        with portal.client("op1") as c:
            wait_until(lambda: len((c.get("/api/operator/arena").json()["fleet"] or {}).get("robots", [])) == 4,
                       timeout=60, what="the fleet's first reading")
        jid = portal.submit("alice", source=SLOW, robots=2, duration=50.0).json()["id"]
        skip_verification(portal, jid)
        wait_until(lambda: svc.job_state(jid) == "running", timeout=120, what="the job running")
        with sync_playwright() as pw:
            b = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            try:
                page = b.new_page(viewport={"width": 1200, "height": 1000})
                browser_sign_in(page, portal, "op1")
                robots = page.eval_on_selector_all("#arena-map g.robot", "gs => gs.map(g => g.getBBox().width)")
                assert len(robots) == 4 and all(w > 0.1 for w in robots)  # drawn, robot-sized (m)
                assert page.locator("#arena-map g.robot-assigned").count() == 2  # the job's two robots
                page.click(f"#arena-state button[data-action=cancel][data-job='{jid}']")
                page.wait_for_url("**/operator")
                wait_until(lambda: svc.job_state(jid) == "cancelled", timeout=30, what="the job cancelled")
                assert not svc.arena_stopped
            finally:
                b.close()
    finally:
        runner.stop()
