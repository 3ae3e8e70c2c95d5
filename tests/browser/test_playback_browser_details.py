"""The player in a real browser: the timeline slider shows hundredths ("2.24", not "2.244000"), the recording's
events are marks on it, goto's goals are drawn, and with the density layer off no contact placeholder dot is
left in the scene (an empty contacts layer is hidden)."""
from __future__ import annotations

import os
import re

import pytest

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
        "--disable-background-networking", "--disable-component-update"]
pytestmark = [pytest.mark.browser,
              pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium")]
NODE = "(name) => { const s = window.__viserSceneTree.getState()[name]; return s ? s.visibility : null; }"


@pytest.fixture(scope="module")
def app(tmp_path_factory):
    from swarmdeck.console.recording.reader import open_recording
    from swarmdeck.console.recording.recorder import Recorder
    from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
    from swarmdeck.console.web.player import PlayerApp

    path = tmp_path_factory.mktemp("details") / "run.mcap"
    loop = ControlLoop(LoopConfig(n_robots=5, seed=1, behaviour="goto"))
    with Recorder(path) as rec:
        for k in range(90):
            if k in (20, 60):
                loop.post({20: "robots look fine", 60: "swap the battery of robot 3"}[k])
            rec.write_frame(loop.tick())
    loop.close()
    recording = open_recording(path)
    player_app = PlayerApp(recording, port=0)
    player_app.scene.set_layer("density", False)
    player_app.player.seek(2.244)
    player_app.refresh(force=True)
    yield player_app
    player_app.close()
    recording.close()


def test_slider_marks_goals_and_no_stray_dot(app):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.goto(f"http://127.0.0.1:{app.port}")
            page.wait_for_function("() => window.__viserSceneTree && window.__viserSceneTree.getState()['/robots']",
                                   polling="raf", timeout=30_000)
            shown = f"{app.player.frame_time:.2f}"
            page.wait_for_function(f"() => Array.from(document.querySelectorAll('input')).some(i => i.value === "
                                   f"'{shown}')", timeout=20_000)
            numbers = [v for v in (i.input_value() for i in page.locator("input").all()) if re.fullmatch(r"\d+\.\d+", v)]
            assert numbers and all(re.fullmatch(r"\d+\.\d{2}", v) for v in numbers), numbers
            assert page.locator(".mantine-Slider-mark").count() == len(app.event_rows) == 2
            assert page.evaluate(NODE, "/goals") is True
            assert page.evaluate(NODE, "/density") is False
            assert page.evaluate(NODE, "/contacts") is False  # no magenta placeholder mid-arena
            assert page.evaluate(NODE, "/centroids") is False
        finally:
            browser.close()
