"""The Plots panel is one drawing code: the live console and the player chart the same Frames identically."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.web.app import ConsoleApp
from swarmdeck.console.web.player import PlayerApp
from swarmdeck.console.web.plots import CHARTS, PlotHistory, frame_sample


@pytest.fixture(scope="module")
def live_and_recorded(tmp_path_factory):
    """60 ticks of a real loop (coverage with the barrier, then rendezvous with the barrier off) drawn
    live by a ConsoleApp, and the same Frames recorded."""
    loop = ControlLoop(LoopConfig(seed=5, n_robots=8))
    app = ConsoleApp(loop, port=0)  # subscribes its viewer: every tick reaches the panel as live
    frames = []
    try:
        for k in range(60):
            if k == 30:
                loop.set_behaviour("rendezvous")  # no coverage state: H and ‖p − c‖ are gaps
                loop.set_safety(enabled=False)
            frames.append(loop.tick())
        app.gui.update(frames[-1], force=True)
        live = {name: tuple(np.array(a) for a in h.data) for name, h in app.gui.plots.handles().items()}
    finally:
        app.close()
    path = tmp_path_factory.mktemp("plots") / "run.mcap"
    with Recorder(path) as rec:
        for f in frames:
            assert rec.write_frame(f)
    return frames, live, path


def test_playback_charts_what_the_live_console_charted(live_and_recorded) -> None:
    frames, live, path = live_and_recorded
    recording = open_recording(path)
    app = PlayerApp(recording, port=0)
    try:
        for _ in frames[1:]:
            app.fwd_button.value = True  # what the browser sends for "Step ▶"
        assert app.player.frame.tick == frames[-1].tick
        played = {name: h.data for name, h in app.plots.handles().items()}
    finally:
        app.close()
        recording.close()
    assert set(live) == set(played) == {name for name, _ in CHARTS}
    for name, _ in CHARTS:
        t_live, *y_live = live[name]
        t_play, *y_play = played[name]
        assert len(t_live) == len(frames)
        np.testing.assert_allclose(t_play, t_live, atol=1e-6)  # recording time is stored in ns
        for a, b in zip(y_play, y_live):
            np.testing.assert_array_equal(np.isnan(a), np.isnan(b))  # NaN gaps in the same places
            # recordings keep display numbers at a display precision (timing to 1 µs = 1e-3 ms)
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-3, equal_nan=True)


def test_the_series_hold_what_the_frames_say(live_and_recorded) -> None:
    frames, live, _ = live_and_recorded
    t, dmin, ds = live["dist"]
    np.testing.assert_allclose(t, [f.time - frames[0].time for f in frames])
    np.testing.assert_array_equal(ds, [f.barrier.safety_distance for f in frames])  # D_s the barrier used
    np.testing.assert_array_equal(dmin, [f.barrier.min_distance for f in frames])
    _, H, mpc = live["H"]
    assert np.all(np.isfinite(H[:30])) and np.all(np.isnan(H[30:])) and np.all(np.isnan(mpc[30:]))


def test_missing_numbers_are_gaps_and_the_window_drops_the_oldest(live_and_recorded) -> None:
    frame = live_and_recorded[0][0]
    bare = dataclasses.replace(frame, barrier=None, coverage=None, timing={})
    assert all(math.isnan(x) for x in frame_sample(bare))  # no barrier record: no "0 active", no made-up D_s
    one = dataclasses.replace(frame, barrier=dataclasses.replace(frame.barrier, min_distance=math.inf))
    assert math.isnan(frame_sample(one)[0])  # fewer than two robots: no distance, a gap
    hist = PlotHistory(window=3)
    for k in range(5):
        hist.add(float(k), frame)
    assert hist.arrays()["t"].tolist() == [2.0, 3.0, 4.0] and hist.last_time == 4.0
    with pytest.raises(ValueError, match="plot window"):
        PlotHistory(window=1)
