"""The console with 1000 robots (10 × 6 m arena) in a real headless browser: the page loads and the
emergency stop works. Assertions on state (the scene tree, the loop's Frames), never on frame rates."""
from __future__ import annotations

import os

import pytest
from test_console_browser import ARGS, CHROMIUM, VIEW, wait_until

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="Debian's chromium is not installed at /usr/bin/chromium "
                       "(scripts/test installs it)"),
]

ROBOTS_DRAWN = """(n) => {
  const s = window.__viserSceneTree && window.__viserSceneTree.getState()['/robots'];
  if (!s) return false;
  const p = s.message.props.batched_positions;
  return p.byteLength === n * 3 * 4;
}"""


def test_page_loads_and_emergency_stop_works_with_1000_robots() -> None:
    from playwright.sync_api import sync_playwright

    from swarmdeck.console.runtime.config import arena_bounds
    from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
    from swarmdeck.console.web.app import ConsoleApp

    app = ConsoleApp(ControlLoop(LoopConfig(seed=3, n_robots=1000, bounds=arena_bounds("10x6"))), port=0).start()
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=ARGS)
            page = browser.new_page(viewport=VIEW)
            page.goto(app.url)
            page.wait_for_function(ROBOTS_DRAWN, arg=1000, timeout=120000)
            names = page.evaluate("() => Object.keys(window.__viserSceneTree.getState())")
            assert "/voronoi" in names and not any(n.startswith("/labels/") for n in names)
            loop = app.loop
            wait_until(lambda: loop.latest.run_state == "running" and not loop.latest.stopped, 120)
            page.get_by_role("button", name="EMERGENCY STOP", exact=True).click()
            wait_until(lambda: loop.latest.run_state == "estop", 60)
            first = loop.latest
            assert first.stopped
            wait_until(lambda: loop.latest.tick >= first.tick + 2, 120)
            assert loop.latest.stopped and loop.latest.run_state == "estop"
            browser.close()
    finally:
        app.close()
