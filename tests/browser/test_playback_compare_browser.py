"""Several recordings in one player, in a real browser (headless Debian chromium): run A drawn as the console
draws, run B as ghosts at its own closed-form poses, both moved by the one timeline; the Runs panel names them
and the plots have a line per run."""
from __future__ import annotations

import os

import numpy as np
import pytest
from compare_synth import straight_run

from swarmdeck.console.recording.reader import open_recording

CHROMIUM = "/usr/bin/chromium"
pytestmark = [pytest.mark.browser,
              pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium")]
ARGS = ["--no-sandbox", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
        "--disable-background-networking", "--disable-component-update"]
TREE = "window.__viserSceneTree.getState()"


def positions(node: str) -> str:
    return f"Array.from({TREE}['{node}'].message.props.batched_positions)"


@pytest.fixture(scope="module")
def app(tmp_path_factory):
    from swarmdeck.console.web.player import PlayerApp

    d = tmp_path_factory.mktemp("compare")
    recs = [open_recording(straight_run(d / "a.mcap", 65, events={16: "go"})),
            open_recording(straight_run(d / "b.mcap", 49, n=4, speed=0.1, events={32: "go"}))]
    player_app = PlayerApp(recs, port=0, offsets=(1.0, 0.0), layout="overlay").start()  # aligned at "go"
    yield player_app
    player_app.close()
    for r in recs:
        r.close()


def _xy(flat):
    return np.asarray(flat, dtype=float).reshape(-1, 3)[:, :2]


def test_two_runs_on_one_timeline(app):
    from playwright.sync_api import sync_playwright

    a, b = app.recordings
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.goto(f"http://127.0.0.1:{app.port}")
            page.wait_for_function(f"() => window.__viserSceneTree && {TREE}['/robots'] && {TREE}['/ghosts/B']",
                                   polling="raf", timeout=30_000)
            np.testing.assert_allclose(_xy(page.evaluate(f"() => {positions('/robots')}")),
                                       a.first_frame.poses[:, :2], atol=1e-6)
            np.testing.assert_allclose(_xy(page.evaluate(f"() => {positions('/ghosts/B')}")),
                                       b.first_frame.poses[:, :2], atol=1e-6)
            assert page.get_by_text("b.mcap (ghost").count() == 1  # the Runs panel names each run
            assert page.get_by_text("B min distance").count() >= 1  # a plot line per run

            # the user clicks three quarters along the timeline (5 s: A from 1 s on, B from 0)
            track = page.locator(".mantine-Slider-root").first
            box = track.bounding_box()
            page.mouse.click(box["x"] + 0.75 * box["width"], box["y"] + box["height"] / 2)
            page.wait_for_function(f"() => Math.abs({positions('/ghosts/B')}[3] - "
                                   f"({b.first_frame.poses[1, 0]})) > 1e-4", polling="raf", timeout=20_000)
            ta, tb = app.player.frame_times  # paused: the click's seek is the last one
            assert app.player.position > 2.0 and tb == pytest.approx(min(ta + 1.0, b.duration))
            for node, rec, t in (("/robots", a, ta), ("/ghosts/B", b, tb)):  # each run at its own time
                want = rec.frame_at(t)[1].poses[:, :2]
                page.wait_for_function(
                    f"() => {{ const p = {positions(node)}; const w = {want.ravel().tolist()}; "
                    "return w.every((v, i) => Math.abs(p[3 * (i >> 1) + (i & 1)] - v) < 1e-5); }",
                    polling="raf", timeout=20_000)
        finally:
            browser.close()
