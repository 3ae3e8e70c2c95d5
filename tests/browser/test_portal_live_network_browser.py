"""The portal's live view (static/live.js in Debian's chromium) draws a decentralised run's communication links
(the Frame's ``network``, the picture's network layer): the page, live.js and a stream of one Frame's message served
over real HTTP on loopback (tests/live_page.py); ``window.swarmdeckLive.links`` counts the links drawn."""
from __future__ import annotations

import os

import numpy as np
import pytest
from live_page import ARGS, CHROMIUM, live_page

from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.network_frame import NetworkFrame

pytestmark = [pytest.mark.browser, pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium")]


def test_the_live_view_draws_the_network_links() -> None:
    from playwright.sync_api import sync_playwright

    n = 3
    frame = Frame(tick=1, time=0.033, poses=np.array([[-1.0, -0.5, 0.0], [0.0, 0.0, 1.0], [0.8, 0.4, 2.0]]),
                  ids=np.arange(n), nominal=np.zeros((n, 2)), safe=np.zeros((n, 2)), v=np.zeros(n), w=np.zeros(n),
                  network=NetworkFrame(np.array([[0, 1], [1, 2]]), np.array([30.0, 0.0])))
    with live_page(frame) as url, sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            page = browser.new_page()
            page.goto(url)
            page.wait_for_function("window.swarmdeckLive && window.swarmdeckLive.frames >= 1", timeout=30_000)
            assert page.evaluate("window.swarmdeckLive.links") == 2
        finally:
            browser.close()
