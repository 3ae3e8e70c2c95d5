"""The multi-run player's panel without a browser: side by side each run has its own scene moved right by an
arena and a gap; overlaid the ghosts follow their run; the plots put each run's line on one time axis."""
from __future__ import annotations

import math

import numpy as np
import pytest
from compare_synth import straight_run

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.web.compare_view import SIDE_GAP, merge_series, side_offsets
from swarmdeck.console.web.player import PlayerApp
from swarmdeck.console.web.plots import PlotHistory
from swarmdeck.core.bounds import Bounds


@pytest.fixture(scope="module")
def recs(tmp_path_factory):
    d = tmp_path_factory.mktemp("side")
    out = [open_recording(straight_run(d / "a.mcap", 33)),
           open_recording(straight_run(d / "b.mcap", 17, n=4, bounds=(-1.2, 1.2, -0.8, 0.8), events={8: "bump"}))]
    yield out
    for r in out:
        r.close()


def test_side_by_side_each_run_has_its_scene_beside_the_one_before(recs):
    app = PlayerApp(recs, port=0, layout="side", offsets=(0.0, 0.5))
    try:
        assert [s.root for s in app.side_scenes] == ["/runB"] and app.ghosts == []
        assert side_offsets([Bounds(-1.6, 1.6, -1, 1), Bounds(-1.2, 1.2, -0.8, 0.8)]) == [0.0, 1.6 + SIDE_GAP + 1.2]
        app.slider.value = 1.0  # the browser's timeline
        (ta, a), (tb, b) = zip(app.player.frame_times, app.player.frames)
        assert (ta, tb) == (1.0, 0.5) and (a.n, b.n) == (3, 4)
        np.testing.assert_allclose(app.side_scenes[0].nodes.robots.batched_positions[:, :2], b.poses[:, :2], atol=1e-6)
        assert "B: t = 0.50 s · tick 8 · 4 robots" in app.status.content
        assert "B: bump" in app.events.content  # the frame's own event, named by its run
        app.slider.value = 0.25  # before B's offset: B not started, no line for it yet
        assert "B: not started" in app.status.content and len(app.histories[1]) == 0
    finally:
        app.close()


def test_overlaid_ghosts_follow_their_run_and_hide(recs):
    app = PlayerApp(recs, port=0, layout="overlay")
    try:
        app.slider.value = 0.75
        ghost = app.ghosts[0]
        np.testing.assert_allclose(ghost.node.batched_positions[:, :2], app.player.frames[1].poses[:, :2], atol=1e-6)
        app._ghost_boxes[0].value = False
        assert ghost.node.visible is False
        with pytest.raises(ValueError, match="layout must be one of overlay, side"):
            PlayerApp(recs, port=0, layout="stacked")
    finally:
        app.close()


def test_plot_lines_share_one_time_axis_and_gap_outside_their_run():
    a, b = PlotHistory(), PlotHistory()
    from compare_synth import straight_frame

    for k in range(4):  # A at 0, 1, 2, 3 s; B at 1.5, 2.5 s
        a.add(float(k), straight_frame(k))
    for k in range(2):
        b.add(1.5 + k, straight_frame(10 + k))
    x, (ya, yb) = merge_series([a, b], "H")
    assert x.tolist() == [0.0, 1.0, 1.5, 2.0, 2.5, 3.0]
    assert ya.tolist() == pytest.approx([1.0, 1.1, 1.1, 1.2, 1.2, 1.3])
    assert [math.isnan(v) for v in yb] == [True, True, False, False, False, True]
    assert yb[2:5].tolist() == pytest.approx([2.0, 2.0, 2.1])
