"""The HTML replay opened in a real browser shows the arena centred (no control panel to make room for): the
camera is above the arena's centre; `swarmdeck export --html` prints no server box."""
from __future__ import annotations

import os

import pytest
from recording_synth import simulated_frames

from swarmdeck.console.cli import main as cli
from swarmdeck.console.recording.recorder import Recorder

CHROMIUM = "/usr/bin/chromium"
pytestmark = [pytest.mark.browser,
              pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium")]
ARGS = ["--no-sandbox", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
        "--disable-background-networking", "--disable-component-update"]
# three.js is y-up: the world's (x, y, z) is three's (x, -z, y), so the arena's centre lies at three x = z = 0
CAMERA = "() => { const c = window.__viserMutable && window.__viserMutable.camera; return c ? [c.position.x, " \
         "c.position.z, c.position.y] : null; }"


def test_the_html_replay_is_centred_on_the_arena(tmp_path, capfd):
    from playwright.sync_api import TimeoutError as PlaywrightTimeout
    from playwright.sync_api import sync_playwright

    path = tmp_path / "run.mcap"
    with Recorder(path) as rec:
        for f in simulated_frames(n_robots=4, n_ticks=20, dt=0.05, seed=3):
            rec.write_frame(f)
    html = tmp_path / "replay.html"
    assert cli(["export", str(path), "--html", str(html)]) == 0
    out = capfd.readouterr().out
    assert "http://" not in out and "Websocket" not in out and "wrote" in out
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            page = browser.new_page(viewport={"width": 1000, "height": 700})
            page.goto(html.as_uri())
            page.wait_for_function("() => window.__viserSceneTree && window.__viserSceneTree.getState()['/robots']",
                                   polling="raf", timeout=30_000)
            page.wait_for_function(f"() => {{ const p = ({CAMERA})(); return p && p[2] > 1; }}", polling="raf",
                                   timeout=30_000)  # the initial top view has arrived (high above the floor)
            # and settled above the centre (bounded: a loaded machine may take seconds; asserted below)
            try:
                page.wait_for_function(
                    f"() => {{ const p = ({CAMERA})(); return Math.abs(p[0]) < 0.02 && Math.abs(p[1]) < 0.02; }}",
                    polling="raf", timeout=20_000)
            except PlaywrightTimeout:
                pass
            x, y, _ = page.evaluate(CAMERA)
        finally:
            browser.close()
    assert abs(x) < 0.02 and abs(y) < 0.02, (x, y)  # above the centre of the (-1.6, 1.6) × (-1, 1) arena
