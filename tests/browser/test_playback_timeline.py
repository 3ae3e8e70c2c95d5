"""Playback in a real browser (headless Debian chromium): the timeline moves the robots, Play plays."""
from __future__ import annotations

import os

import numpy as np
import pytest
from recording_synth import simulated_frames

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder

CHROMIUM = "/usr/bin/chromium"
pytestmark = [pytest.mark.browser,
              pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium")]
ARGS = ["--no-sandbox", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
        "--disable-background-networking", "--disable-component-update"]
POSITIONS = "() => Array.from(window.__viserSceneTree.getState()['/robots'].message.props.batched_positions)"


@pytest.fixture(scope="module")
def app(tmp_path_factory):
    from swarmdeck.console.web.player import PlayerApp

    path = tmp_path_factory.mktemp("play") / "run.mcap"
    rec = Recorder(path)
    for f in simulated_frames(n_robots=6, n_ticks=90, dt=0.033, seed=5):
        rec.write_frame(f)
    rec.close()
    recording = open_recording(path)
    player_app = PlayerApp(recording, port=0).start()
    yield player_app
    player_app.close()
    recording.close()


def _xy(flat):
    return np.asarray(flat, dtype=float).reshape(-1, 3)[:, :2]


def _shown_and_wanted(page, app, rec):
    """The robots' positions the page shows and those of the recording at the player's time."""
    return _xy(page.evaluate(POSITIONS)), rec.frame_at(app.player.frame_time)[1].poses[:, :2]


def test_timeline_moves_the_robots(app):
    from playwright.sync_api import sync_playwright

    rec = app.recording
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.goto(f"http://127.0.0.1:{app.port}")
            page.wait_for_function("() => window.__viserSceneTree && window.__viserSceneTree.getState()['/robots']",
                                   polling="raf", timeout=30_000)
            start = _xy(page.evaluate(POSITIONS))
            np.testing.assert_allclose(start, rec.first_frame.poses[:, :2], atol=1e-6)

            # the user clicks three quarters along the timeline slider
            # (a loaded machine may still be laying the panel out: the click is repeated, boundedly, until the
            # player has moved — what is asserted is where it moved to, not how fast)
            track = page.locator(".mantine-Slider-root").first
            for _ in range(5):
                box = track.bounding_box()
                page.mouse.click(box["x"] + 0.75 * box["width"], box["y"] + box["height"] / 2)
                for _ in range(100):
                    if app.player.position > 0.5 * app.player.duration:
                        break
                    page.wait_for_timeout(100)
                else:
                    continue
                break
            page.wait_for_function(
                f"() => {{ const p = {POSITIONS[6:]}; return Math.abs(p[0] - ({start[0, 0]})) > 1e-4; }}",
                polling="raf", timeout=30_000)
            assert app.player.position > 0.5 * app.player.duration
            # the scene shows the frame at the player's time once its last update lands (a loaded machine
            # may take seconds: wait for the state, bounded, rather than a fixed pause)
            shown, want = _shown_and_wanted(page, app, rec)
            for _ in range(200):
                if np.allclose(shown, want, atol=1e-6):
                    break
                page.wait_for_timeout(100)
                shown, want = _shown_and_wanted(page, app, rec)
            np.testing.assert_allclose(shown, want, atol=1e-6)

            # Play: the robots move on from where the timeline is
            here = shown
            page.get_by_role("button", name="Play").click()
            page.wait_for_function(
                f"() => {{ const p = {POSITIONS[6:]}; return Math.abs(p[0] - ({here[0, 0]})) > 1e-5 "
                f"|| Math.abs(p[1] - ({here[0, 1]})) > 1e-5; }}", polling="raf", timeout=20_000)
            assert app.player.frame_time > 0.5 * app.player.duration
        finally:
            browser.close()
