"""The playback timeline: play at a rate, pause, step, seek, loop and the A/B range, on a virtual clock."""
from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from recording_synth import simulated_frames

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
from swarmdeck.console.web.player import Player

DT = 0.05
N = 101  # 5 s


@pytest.fixture(scope="module")
def path(tmp_path_factory):
    p = tmp_path_factory.mktemp("player") / "p.mcap"
    rec = Recorder(p, config=RecorderConfig(chunk_size=4000))
    for f in simulated_frames(n_robots=3, n_ticks=N, dt=DT, coverage=False):
        rec.write_frame(f)
    rec.close()
    return p


@pytest.fixture
def player(path):
    with open_recording(path) as r:
        yield Player(r, clock=lambda: 0.0)


def test_play_advances_by_rate_times_clock_time(player):
    p = player
    assert p.duration == pytest.approx((N - 1) * DT)
    p.set_rate(2.0)
    p.play()
    p.update(10.0)                      # first update starts the clock
    assert p.update(10.5)               # 0.5 s × 2 = 1.0 s of recording
    assert p.position == pytest.approx(1.0)
    assert p.frame.tick == 20 and p.frame_time == pytest.approx(1.0)
    p.pause()
    assert not p.update(20.0) and p.position == pytest.approx(1.0)
    p.set_rate(0.1)
    p.play()
    p.update(30.0)
    p.update(31.0)
    assert p.position == pytest.approx(1.1)


def test_rate_is_limited_to_a_tenth_to_four(player):
    for bad in (0.05, 4.5, 0.0, -1.0):
        with pytest.raises(ValueError, match="rate"):
            player.set_rate(bad)
    player.set_rate(0.1)
    player.set_rate(4)


def test_end_stops_or_loops(player):
    p = player
    p.seek(4.9)
    p.play()
    p.update(0.0)
    p.update(1.0)
    assert not p.playing and p.position == pytest.approx(p.duration) and p.frame.tick == N - 1
    p.play()                            # at the end: play restarts from the start
    assert p.position == 0.0 and p.frame.tick == 0
    p.set_loop(True)
    p.update(0.0)
    p.update(5.3)                       # 5.3 s past 0 on a 5 s recording → 0.3 s
    assert p.playing and p.position == pytest.approx(0.3)


def test_ab_range_bounds_playback(player):
    p = player
    p.seek(1.0)
    p.set_a()
    p.seek(2.0)
    p.set_b()
    assert p.range == (pytest.approx(1.0), pytest.approx(2.0))
    p.set_loop(True)
    p.play()                            # at B: starts again from A
    assert p.position == pytest.approx(1.0)
    p.update(0.0)
    p.update(1.25)
    assert p.position == pytest.approx(1.25)
    p.set_loop(False)
    p.update(3.0)
    assert not p.playing and p.position == pytest.approx(2.0)
    with pytest.raises(ValueError, match="A < B"):
        p.set_range(3.0, 2.0)
    p.clear_range()
    assert p.range == (0.0, pytest.approx(p.duration))


def test_step_moves_one_frame_and_pauses(player):
    p = player
    p.seek(2.0)
    p.play()
    assert p.step(1).tick == 41 and not p.playing
    assert p.step(-3).tick == 38
    assert p.step(-1000).tick == 0
    assert p.step(1000).tick == N - 1


def test_seek_clamps_and_rejects_nan(player):
    assert player.seek(-5.0).tick == 0
    assert player.seek(1e6).tick == N - 1
    with pytest.raises(ValueError, match="finite"):
        player.seek(float("nan"))


@settings(max_examples=40, deadline=None)
@given(ops=st.lists(st.tuples(st.sampled_from(["play", "pause", "seek", "step", "rate", "tick"]),
                              st.floats(0.0, 1.0)), max_size=25))
def test_shown_frame_is_always_the_frame_at_the_position(path, ops):
    with open_recording(path) as r:
        p = Player(r, clock=lambda: 0.0)
        now = 0.0
        for op, x in ops:
            if op == "play":
                p.play()
            elif op == "pause":
                p.pause()
            elif op == "seek":
                p.seek(x * 6.0 - 0.5)
            elif op == "step":
                p.step(1 if x > 0.5 else -1)
            elif op == "rate":
                p.set_rate(0.1 + 3.9 * x)
            else:
                now += x
                p.update(now)
            assert 0.0 <= p.position <= p.duration + 1e-12
            assert p.frame.tick == r.frame_at(p.position)[1].tick
