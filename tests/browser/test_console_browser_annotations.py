"""What an experiment draws appears in the console in a real browser (issue 29 item 3): a behaviour that draws
(as the portal's sandboxed script does, ``DrawsAnnotations``) puts its annotations into the loop's Frames and
the browser's scene tree holds the ``annotations`` layer's segments, points and text. Assertions are on the
browser's scene state, never on frame rates; a screenshot is kept in ``test-artifacts/console-annotations.png``."""
from __future__ import annotations

import os
import time
from pathlib import Path

import numpy as np
import pytest

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
        "--disable-background-networking", "--disable-component-update"]
ARTIFACTS = Path(__file__).resolve().parents[2] / "test-artifacts"
pytestmark = [pytest.mark.browser,
              pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium at /usr/bin/chromium")]

SEGMENT_FROM = """() => {
  const s = window.__viserSceneTree && window.__viserSceneTree.getState()['/annotations/lines'];
  if (!s) return null;
  const p = s.message.props.points;
  const a = new Float32Array(p.buffer, p.byteOffset, p.byteLength / 4);
  return a.length >= 6 ? [a.length / 6, a[0], a[1], a[3], a[4]] : null;
}"""
LABEL = """() => {
  const s = window.__viserSceneTree && window.__viserSceneTree.getState()['/annotations/text0'];
  return s ? [s.message.props.text, s.message.props.visible !== false] : null;
}"""


class Drawing:
    """A behaviour that holds the robots still and draws a line, a ring, a dot and a caption."""

    name = "drawing"

    def __init__(self) -> None:
        from swarmdeck.core.annotator import Annotator

        self.draw = Annotator()
        self.draw.line((-1.0, -0.5), (1.0, 0.5), color="magenta", width=0.02)
        self.draw.circle((0.5, -0.5), 0.2, color="green")
        self.draw.point((-0.5, 0.5), radius=0.04, color="blue")
        self.draw.text((0.0, 0.8), "hello floor", height=0.1)

    def __call__(self, tick):
        return np.zeros((len(tick.poses), 2)), None

    def annotations(self, time: float):
        return self.draw.collect(time)


def test_the_console_shows_what_the_experiment_draws():
    from playwright.sync_api import sync_playwright

    from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
    from swarmdeck.console.web.app import ConsoleApp

    app = ConsoleApp(ControlLoop(LoopConfig(seed=11, n_robots=4)), port=0).start()
    try:
        app.loop.use_behaviour(Drawing())
        app.loop.run()
        deadline = time.monotonic() + 30
        while (app.loop.latest is None or app.loop.latest.annotations is None) and time.monotonic() < deadline:
            time.sleep(0.02)
        assert app.loop.latest.annotations is not None and len(app.loop.latest.annotations) == 4
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=ARGS)
            try:
                page = browser.new_page(viewport={"width": 1280, "height": 800})
                page.goto(app.url)
                page.wait_for_function(f"() => ({SEGMENT_FROM})() !== null", timeout=60_000)
                count, x0, y0, x1, y1 = page.evaluate(SEGMENT_FROM)
                assert count == 1 + 32  # the line and the ring's 32 segments
                assert (x0, y0, x1, y1) == pytest.approx((-1.0, -0.5, 1.0, 0.5), abs=1e-6)
                page.wait_for_function(f"() => {{ const l = ({LABEL})(); return l !== null && l[0] === 'hello floor'; }}",
                                       timeout=30_000)
                assert page.evaluate(LABEL) == ["hello floor", True]
                ARTIFACTS.mkdir(exist_ok=True)
                page.screenshot(path=str(ARTIFACTS / "console-annotations.png"))
            finally:
                browser.close()
    finally:
        app.close()
