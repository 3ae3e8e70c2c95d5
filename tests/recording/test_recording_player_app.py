"""The player's panel without a browser: GUI values drive the timeline, the scene draws the frame shown."""
from __future__ import annotations

import numpy as np
import pytest
from recording_synth import simulated_frames

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder
from swarmdeck.console.web.player import PLOT_BACKFILL, PlayerApp


@pytest.fixture(scope="module")
def app(tmp_path_factory):
    path = tmp_path_factory.mktemp("app") / "a.mcap"
    with Recorder(path) as rec:
        for f in simulated_frames(n_robots=5, n_ticks=300, dt=0.033, seed=8, coverage=False):
            rec.write_frame(f)
    recording = open_recording(path)
    a = PlayerApp(recording, port=0)
    yield a
    a.close()
    recording.close()


def test_slider_seeks_and_the_scene_draws_that_frame(app):
    drawn = app.scene.frames_drawn
    app.slider.value = 7.0  # what a browser sends when the user drags the timeline
    assert app.player.frame.tick == 212 and app.scene.frames_drawn == drawn + 1
    robots = app.scene.nodes.robots
    np.testing.assert_allclose(robots.batched_positions[:, :2], app.player.frame.poses[:, :2], atol=1e-6)
    t = app.plots.dist.data[0]
    assert t[-1] == pytest.approx(app.player.frame_time) and t[0] == pytest.approx(7.0 - PLOT_BACKFILL, abs=0.04)
    assert "tick 212" in app.status.content


def test_rate_loop_and_layers_from_the_panel(app):
    app.rate.value = "0.25x"
    assert app.player.rate == 0.25
    app.loop.value = True
    assert app.player.loop
    app._layer_boxes["voronoi"].value = False
    assert not app.scene.visible["voronoi"]
    app._layer_boxes["voronoi"].value = True


def test_ab_buttons_report_the_range(app):
    app.player.seek(2.0)
    app._range(app.player.set_a)
    app.player.seek(1.0)
    app._range(app.player.set_b)  # B before A: A is dropped
    assert app.player.range == (0.0, pytest.approx(1.0))
    assert app.range_text.content.startswith("A/B: 0.00 s")
    app._range(app.player.clear_range)
    assert app.range_text.content == "A/B: whole recording"
