"""What the running job draws appears in the portal's live view in a real browser (issue 29 item 3): Frames with
annotations published to the arena's LiveFeed reach the job page's canvas, which draws every primitive — the
canvas's pixels at a filled square are its colour, and ``window.swarmdeckLive`` says how many primitives and which
texts it drew. A screenshot is kept in ``test-artifacts/portal-live-annotations.png``."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from portal_fixtures import browser_sign_in, make_portal, skip_verification

from swarmdeck.console.runtime.frame import Frame
from swarmdeck.core.annotations import CIRCLE, POINT, POLYGON, POLYLINE, TEXT, Annotations

CHROMIUM = "/usr/bin/chromium"
ARTIFACTS = Path(__file__).resolve().parents[2] / "test-artifacts"
ARGS = ["--no-sandbox", "--disable-background-networking", "--disable-component-update"]
pytestmark = [pytest.mark.browser, pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium")]

ANN = Annotations(kinds=[POLYGON, CIRCLE, POINT, POLYLINE, TEXT], offsets=[0, 4, 5, 6, 8, 9],
                  vertices=[[-1.4, -0.9], [-0.8, -0.9], [-0.8, -0.3], [-1.4, -0.3], [0.8, -0.5], [0.2, 0.6],
                            [-0.5, 0.2], [0.5, 0.2], [1.0, 0.7]],
                  sizes=[0.01, 0.2, 0.05, 0.02, 0.1],
                  colors=[[230, 20, 20, 255], [20, 180, 20, 255], [20, 20, 220, 255], [200, 0, 200, 255], [0, 0, 0, 255]],
                  filled=[True, False, True, False, False], texts=("", "", "", "", "goal 1"))
PIXEL = """() => {
  const c = document.getElementById('live');
  const ctx = c.getContext('2d');
  const [x0, x1, y0, y1] = [-1.6, 1.6, -1.0, 1.0];
  const s = Math.min(c.width / (x1 - x0), c.height / (y1 - y0));
  const ox = (c.width - s * (x1 - x0)) / 2, oy = (c.height - s * (y1 - y0)) / 2;
  const d = ctx.getImageData(Math.round(ox + (-1.1 - x0) * s), Math.round(oy + (y1 - (-0.6)) * s), 1, 1).data;
  return [d[0], d[1], d[2]];
}"""


def frame(tick: int) -> Frame:
    poses = np.array([[1.3, -0.8, 0.0], [-1.3, 0.8, 0.0]])
    return Frame(tick=tick, time=tick * 0.033, run_time=tick * 0.033, poses=poses, ids=np.arange(2),
                 nominal=np.zeros((2, 2)), safe=np.zeros((2, 2)), v=np.zeros(2), w=np.zeros(2), annotations=ANN)


def test_the_live_view_draws_what_the_job_draws(tmp_path):
    from playwright.sync_api import sync_playwright

    portal = make_portal(tmp_path, fleet=6, max_duration=60.0, max_upload_bytes=64 << 10)
    try:
        jid = portal.submit("alice", robots=2, duration=5.0).json()["id"]
        skip_verification(portal, jid)
        svc = portal.service
        with svc.db.transaction() as tx:  # as the arena runner moves it (no runner here: the test publishes)
            for state in ("setting up", "running"):
                svc.db.transition(tx, jid, state)
        live = portal.server.server.config.app.state.live
        live.publish(jid, frame(0))
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            try:
                page = browser.new_page(viewport={"width": 1200, "height": 900})
                browser_sign_in(page, portal, "alice")
                page.goto(f"{portal.url}/jobs/{jid}")
                page.wait_for_function("() => window.swarmdeckLive && window.swarmdeckLive.frames > 0", timeout=60_000)
                live.publish(jid, frame(1))
                page.wait_for_function("() => window.swarmdeckLive.annotations === 5", timeout=30_000)
                assert page.evaluate("() => swarmdeckLive.texts") == ["goal 1"]
                assert page.evaluate(PIXEL) == [230, 20, 20]  # inside the filled square
                ARTIFACTS.mkdir(exist_ok=True)
                page.screenshot(path=str(ARTIFACTS / "portal-live-annotations.png"))
            finally:
                browser.close()
    finally:
        portal.server.stop()
        portal.service.close()
