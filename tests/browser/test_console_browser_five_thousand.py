"""The console with 5000 robots on a 22 × 13 m floor (issue 27 item 2: ``swarmdeck console --robots 5000
--arena 22x13``), coverage on its two worker threads (``coverage_worker = "auto"``), in a real headless browser: the page loads, draws every
robot, and the emergency stop stops them. Assertions on state (the scene tree, the loop's Frames), never
on frame rates."""
from __future__ import annotations

import os

import pytest
from test_console_browser import ARGS, CHROMIUM, VIEW, wait_until
from test_console_browser_thousand import ROBOTS_DRAWN

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="Debian's chromium is not installed at /usr/bin/chromium "
                       "(scripts/test installs it)"),
]

N = 5000


def test_page_loads_and_emergency_stop_works_with_5000_robots() -> None:
    from playwright.sync_api import sync_playwright

    from swarmdeck.console.runtime.config import arena_bounds
    from swarmdeck.console.runtime.coverage_worker import PipelinedCoverage
    from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
    from swarmdeck.console.web.app import ConsoleApp

    loop = ControlLoop(LoopConfig(seed=3, n_robots=N, bounds=arena_bounds("22x13")))
    assert isinstance(loop._behaviour, PipelinedCoverage)  # "auto" at this size
    app = ConsoleApp(loop, port=0).start()
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=ARGS)
            page = browser.new_page(viewport=VIEW)
            page.goto(app.url)
            page.wait_for_function(ROBOTS_DRAWN, arg=N, timeout=120000)
            wait_until(lambda: loop.latest is not None and loop.latest.run_state == "running"
                       and loop.latest.coverage is not None and not loop.latest.stopped, 120)
            assert loop.latest.coverage.centroids.shape == (N, 2)
            page.get_by_role("button", name="EMERGENCY STOP", exact=True).click(timeout=120000)
            wait_until(lambda: loop.latest.run_state == "estop", 60)
            first = loop.latest
            assert first.stopped
            wait_until(lambda: loop.latest.tick >= first.tick + 2, 120)
            assert loop.latest.stopped and loop.latest.run_state == "estop"
            browser.close()
    finally:
        app.close()
