"""The HTML export is a standalone replay: opened from disk in a real browser, the robots play back."""
from __future__ import annotations

import os

import numpy as np
import pytest
from recording_synth import simulated_frames

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder
from swarmdeck.console.web.export_html import export_html

CHROMIUM = "/usr/bin/chromium"
pytestmark = [pytest.mark.browser,
              pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium")]
ARGS = ["--no-sandbox", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
        "--disable-background-networking", "--disable-component-update"]
POSITIONS = "Array.from(window.__viserSceneTree.getState()['/robots'].message.props.batched_positions)"


def test_exported_html_replays_the_recording_without_a_server(tmp_path):
    from playwright.sync_api import sync_playwright

    path = tmp_path / "run.mcap"
    frames = list(simulated_frames(n_robots=4, n_ticks=60, dt=0.05, seed=3))
    with Recorder(path) as rec:
        for f in frames:
            rec.write_frame(f)
    with open_recording(path) as r:
        html, drawn = export_html(r, tmp_path / "replay.html", fps=10.0)
    assert drawn == 30
    exported = [f.poses[:, :2] for f in frames[::2]]  # 20 fps recorded, 10 fps exported
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            page = browser.new_page(viewport={"width": 1000, "height": 700})
            page.goto(html.as_uri())  # a file: no viser server anywhere
            page.wait_for_function("() => window.__viserSceneTree && window.__viserSceneTree.getState()['/robots']",
                                   polling="raf", timeout=30_000)
            first = np.asarray(page.evaluate(f"() => {POSITIONS}")).reshape(-1, 3)[:, :2]
            page.wait_for_function(f"() => {{ const p = {POSITIONS}; return Math.abs(p[0] - ({first[0, 0]})) > 1e-5 "
                                   f"|| Math.abs(p[1] - ({first[0, 1]})) > 1e-5; }}", polling=100, timeout=30_000)
            later = np.asarray(page.evaluate(f"() => {POSITIONS}")).reshape(-1, 3)[:, :2]
        finally:
            browser.close()
    # both states shown are exported frames, and the replay moved on to another one (it loops)
    i = {k for k, p in enumerate(exported) if np.allclose(p, first, atol=1e-6)}
    j = {k for k, p in enumerate(exported) if np.allclose(p, later, atol=1e-6)}
    assert i and j and i != j
