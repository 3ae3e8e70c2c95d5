"""A running portal job with sensors and obstacles (``swarmdeck server --sensors --obstacles``) in a real browser
(Debian's chromium, Playwright, real uvicorn and the arena runner on loopback): the job page's live view draws the
robots' ToF rays (``window.swarmdeckLive.rays``) and the floor's obstacle, the canvas in the obstacle's colour where
the wall is. Screenshot: ``test-artifacts/portal-live-sensors.png``."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from portal_fixtures import browser_sign_in, make_portal, skip_verification

from swarmdeck.console.picture.colours import OBSTACLE
from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.core.obstacles import Obstacles

CHROMIUM = "/usr/bin/chromium"
ARTIFACTS = Path(__file__).resolve().parents[2] / "test-artifacts"
ARGS = ["--no-sandbox", "--disable-background-networking", "--disable-component-update"]
pytestmark = [pytest.mark.browser,
              pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium"),
              pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")]

WALL = Obstacles([[[-0.6, 0.35], [0.6, 0.35]]])
STILL = ("import numpy as np\ndef experiment(arena):\n    while True:\n"
         "        arena.set_unicycle(np.zeros(arena.n), np.zeros(arena.n))\n        arena.step()\n")
POSES = [[-0.3, -0.05, 1.5708], [0.3, -0.05, 1.5708]]
WALL_PIXEL = """() => {
  const c = document.getElementById('live'), [x0, x1, y0, y1] = [-1.6, 1.6, -1.0, 1.0];
  const s = Math.min(c.width / (x1 - x0), c.height / (y1 - y0));
  const ox = (c.width - s * (x1 - x0)) / 2, oy = (c.height - s * (y1 - y0)) / 2;
  const px = Math.round(ox + (-0.45 - x0) * s), py = Math.round(oy + (y1 - 0.35) * s);
  return Array.from(c.getContext('2d').getImageData(px, py, 1, 1).data);
}"""


def test_the_live_view_of_a_running_job_draws_its_sensors_rays_and_the_obstacle(tmp_path):
    from playwright.sync_api import sync_playwright

    portal = make_portal(tmp_path, fleet=4, max_duration=60.0)
    svc = portal.service
    live = portal.server.server.config.app.state.live
    runner = ArenaRunner(svc, ArenaSettings(fleet=4, seed=1, obstacles=WALL, sensors=True), live, poll_s=0.1)
    svc.arena = runner  # real time: the job runs long enough to be watched
    runner.start()
    try:
        jid = portal.submit("alice", source=STILL, robots=2, duration=30.0, initial_poses=POSES).json()["id"]
        skip_verification(portal, jid)
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            try:
                page = browser.new_page(viewport={"width": 1200, "height": 900})
                browser_sign_in(page, portal, "alice")
                page.goto(f"{portal.url}/jobs/{jid}")
                page.wait_for_function("() => window.swarmdeckLive && window.swarmdeckLive.rays > 0", timeout=180_000)
                assert page.evaluate("() => swarmdeckLive.rays") <= 2 * 7  # the detections of seven ToF sensors each
                assert page.evaluate("() => swarmdeckLive.obstacles") == 1
                rgba = page.evaluate(WALL_PIXEL)
                assert np.abs(np.array(rgba[:3]) - np.array(OBSTACLE)).sum() < 30, rgba
                ARTIFACTS.mkdir(exist_ok=True)
                page.screenshot(path=str(ARTIFACTS / "portal-live-sensors.png"))
            finally:
                browser.close()
        runner.cancel(jid)
    finally:
        runner.stop()
        portal.server.stop()
        svc.close()
