"""The portal's live view (static/live.js in Debian's chromium) draws the Frame's line-segment obstacles in the
picture's obstacle colour where they are: the page, live.js and a stream of one Frame's message served over real
HTTP on loopback (tests/live_page.py), the canvas read back pixel by pixel."""
from __future__ import annotations

import os

import numpy as np
import pytest
from live_page import ARGS, CHROMIUM, HEIGHT, WIDTH, live_page

from swarmdeck.console.picture.colours import OBSTACLE
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.core.obstacles import Obstacles

pytestmark = [pytest.mark.browser, pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium")]

OBS = Obstacles([[[-1.2, 0.6], [1.2, 0.6]], [[0.8, -0.8], [0.8, 0.2]]])


def test_the_live_view_draws_the_obstacles() -> None:
    from playwright.sync_api import sync_playwright

    n = 2
    frame = Frame(tick=1, time=0.033, poses=np.array([[-1.0, -0.5, 0.0], [0.0, 0.0, 1.0]]), ids=np.arange(n),
                  nominal=np.zeros((n, 2)), safe=np.zeros((n, 2)), v=np.zeros(n), w=np.zeros(n), obstacles=OBS)
    with live_page(frame) as url, sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            page = browser.new_page()
            page.goto(url)
            page.wait_for_function("window.swarmdeckLive && window.swarmdeckLive.frames >= 1", timeout=30_000)
            assert page.evaluate("window.swarmdeckLive.obstacles") == 2
            # the canvas mapping of live.js: fit the arena, centred
            x0, x1, y0, y1 = -1.6, 1.6, -1.0, 1.0
            s = min(WIDTH / (x1 - x0), HEIGHT / (y1 - y0))
            ox, oy = (WIDTH - s * (x1 - x0)) / 2, (HEIGHT - s * (y1 - y0)) / 2
            for (ax, ay), (bx, by) in OBS.segments:
                mx, my = (ax + bx) / 2 + 0.1 * (bx - ax), (ay + by) / 2 + 0.1 * (by - ay)  # off the grid lines
                px, py = round(ox + (mx - x0) * s), round(oy + (y1 - my) * s)
                rgba = page.evaluate(f"Array.from(document.getElementById('live').getContext('2d')"
                                     f".getImageData({px}, {py}, 1, 1).data)")
                assert np.abs(np.array(rgba[:3]) - np.array(OBSTACLE)).sum() < 30, (px, py, rgba)
        finally:
            browser.close()
