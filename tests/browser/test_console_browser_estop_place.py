"""In a real browser: a failing script fills the event list, and the E-STOP stays where the hand expects it (the
panel's first button, not pushed down); repeats show as one line "× N"; after a release the button and the
status line say the robots stay paused until Run."""
from __future__ import annotations

import os
import time

import pytest

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
        "--disable-background-networking", "--disable-component-update"]
VIEW = {"width": 1280, "height": 800}

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="Debian's chromium is not installed at /usr/bin/chromium "
                       "(scripts/test installs it)"),
]


def wait_until(cond, timeout: float = 30.0) -> None:
    deadline = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > deadline:
            raise AssertionError("condition not reached within the timeout")
        time.sleep(0.02)


def settled_box(page, locator, timeout: float = 30.0) -> dict:
    """The element's box once two reads 0.3 s apart agree (the page's first layout has settled)."""
    deadline = time.monotonic() + timeout
    last = locator.bounding_box()
    while True:
        page.wait_for_timeout(300)
        box = locator.bounding_box()
        if box == last:
            return box
        if time.monotonic() > deadline:
            raise AssertionError(f"the element kept moving for {timeout} s: {last} → {box}")
        last = box


def test_the_estop_stays_put_while_a_failing_script_fills_the_events(tmp_path):
    from playwright.sync_api import sync_playwright

    from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
    from swarmdeck.console.web.app import ConsoleApp

    script = tmp_path / "bad.py"
    script.write_text("def behaviour(poses, t):\n    raise ValueError(f'cannot steer at t={t:.3f} s: ' + 'x' * 80)\n")
    loop = ControlLoop(LoopConfig(n_robots=4, seed=1))
    app = ConsoleApp(loop, port=0).start()
    try:
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=ARGS)
            try:
                page = browser.new_page(viewport=VIEW)
                page.goto(app.url)
                estop = page.get_by_role("button", name="EMERGENCY STOP", exact=True)
                estop.wait_for(timeout=60000)
                page.get_by_text("RUNNING").first.wait_for(timeout=30000)
                before = settled_box(page, estop)  # the panel's first layout can still move it (CI saw y 694 → 65)
                loop.set_behaviour(f"script:{script}")
                for k in range(6):  # other events between the repeats, as an operator would add
                    loop.post(f"note {k}: the operator looked at the arena for a while and wrote this down")
                    time.sleep(0.1)
                wait_until(lambda: loop.errors.get("behaviour", 0) >= 30)
                page.get_by_text("cannot steer at t=", exact=False).first.wait_for(timeout=30000)
                page.wait_for_timeout(600)  # the panel refreshes every 0.25 s (state asserted below, not timing)
                after = estop.bounding_box()
                assert abs(after["y"] - before["y"]) < 1.0, (before, after)  # not pushed down by the events
                page.get_by_text("× ", exact=False).first.wait_for(timeout=30000)
                status = page.get_by_text("ticks/s", exact=False).first.bounding_box()
                run = page.get_by_role("button", name="Run", exact=True).bounding_box()
                assert after["y"] < status["y"] < run["y"]  # the first thing in the panel, above what grows
                estop.click()
                wait_until(lambda: loop.latest.run_state == "estop")
                release = page.get_by_role("button", name="Release emergency stop (stays paused: then Run)")
                release.click()
                wait_until(lambda: loop.latest.run_state == "paused")
                page.get_by_text("press Run to resume").first.wait_for(timeout=30000)
            finally:
                browser.close()
    finally:
        app.close()
