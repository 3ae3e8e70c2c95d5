"""Several recordings on one timeline (issue 31 item 4): the anchors, the offsets and what each run shows at a
timeline time, against closed form on synthetic recordings (compare_synth: frames every 1/16 s, exact)."""
from __future__ import annotations

import math

import pytest
from compare_synth import DT, straight_run
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.console.recording.align import (
    Anchor,
    align,
    anchor_time,
    anchors_for,
    offsets_for,
    parse_anchor,
    timeline_duration,
)
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.web.player import Player, timeline_events

SPEED, X0 = 0.2, 0.5


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """A: 4 s, event "go" at 1 s; B: 3 s, "go" at 2 s; C: 2 s, no "go"."""
    d = tmp_path_factory.mktemp("timeline")
    paths = (straight_run(d / "a.mcap", 65, events={16: "go", 40: "e-stop"}),
             straight_run(d / "b.mcap", 49, events={32: "go"}),
             straight_run(d / "c.mcap", 33, events={4: "note"}))
    recs = [open_recording(p) for p in paths]
    yield recs
    for r in recs:
        r.close()


def test_anchors_parse_and_say_what_is_wrong():
    assert parse_anchor("start") == Anchor()
    assert parse_anchor("t:12.5") == Anchor("t", seconds=12.5)
    assert parse_anchor("event:behaviour: goto") == Anchor("event", name="behaviour: goto")
    for bad, why in (("t:abc", "number of seconds"), ("t:-1", "≥ 0"), ("t:nan", "finite"), ("event:", "event's text"),
                     ("middle", "start | t:SECONDS | event:NAME")):
        with pytest.raises(ValueError, match=why):
            parse_anchor(bad)
    assert anchors_for([], 3) == [Anchor()] * 3
    assert anchors_for(["t:1"], 2) == [Anchor("t", 1.0)] * 2
    with pytest.raises(ValueError, match="once per recording"):
        anchors_for(["t:1", "t:2"], 3)


def test_aligned_at_an_event_the_offsets_are_the_anchor_gaps(runs):
    a, b, _ = runs
    assert [anchor_time(r, Anchor("event", name="go")) for r in (a, b)] == [1.0, 2.0]
    offsets = align([a, b], [Anchor("event", name="go")] * 2)
    assert offsets == (1.0, 0.0)  # B's "go" is later: A starts 1 s into the timeline
    assert timeline_duration(offsets, [a.duration, b.duration]) == 5.0  # A ends at 1 + 4 s
    assert align([a, b], [Anchor("t", seconds=0.5), Anchor("t", seconds=1.5)]) == (1.0, 0.0)
    assert align([a, b], [Anchor()] * 2) == (0.0, 0.0)


def test_an_anchor_a_run_lacks_is_an_error_naming_the_file(runs):
    a, _, c = runs
    with pytest.raises(ValueError, match=r"c\.mcap: no event contains 'go' \(first events: 0\.25 s note\)"):
        align([a, c], [Anchor("event", name="go")] * 2)
    with pytest.raises(ValueError, match=r"c\.mcap: --align t:9 is past its end \(2\.00 s\)"):
        anchor_time(c, Anchor("t", seconds=9.0))


def _x1(rec_time: float) -> float:
    """Robot 1's x at a recording time (the frame at or before it: ticks every DT)."""
    k = math.floor(rec_time / DT + 1e-9)
    return X0 - SPEED * k * DT


@settings(max_examples=40, deadline=None)
@given(tau=st.floats(min_value=-1.0, max_value=6.0, allow_nan=False))
def test_each_run_shows_its_frame_at_timeline_time_minus_its_offset(runs, tau):
    a, b, _ = runs
    p = Player([a, b], clock=lambda: 0.0, offsets=(1.0, 0.0))
    assert p.duration == 5.0
    p.seek(tau)
    pos = min(max(tau, 0.0), 5.0)
    for rec, off, frame, t in zip((a, b), (1.0, 0.0), p.frames, p.frame_times):
        rt = min(max(pos - off, 0.0), rec.duration)  # before its offset: its first frame; after its end: its last
        assert t == pytest.approx(math.floor(rt / DT + 1e-9) * DT)
        assert frame.poses[1, 0] == pytest.approx(_x1(rt))
    assert p.frame is p.frames[0]


def test_stepping_visits_every_run_s_frames_in_timeline_order(runs):
    a, b, _ = runs
    p = Player([a, b], clock=lambda: 0.0, offsets=(0.5, 0.0))  # A's frames at 0.5 + k/16, B's at k/16
    seen = [p.frame_time]
    while True:
        before = p.position
        p.step(1)
        if p.position == before:
            break
        seen.append(p.position)
    # the union of both runs' frame times on the timeline (A's coincide with B's: both on the 1/16 s grid)
    assert seen == [k * DT for k in range(int(4.5 / DT) + 1)]
    p.step(-3)
    assert p.position == 4.5 - 3 * DT and p.frame_times == (4.0 - 3 * DT, 3.0)


def test_playing_advances_every_run_and_one_run_is_unchanged(runs):
    a, b, _ = runs
    p = Player([a, b], clock=lambda: 0.0, offsets=(1.0, 0.0))
    p.play()
    p.update(0.0)
    assert p.update(1.5)
    assert p.frame_times == (0.5, 1.5)
    single = Player(a, clock=lambda: 0.0)
    assert single.recordings == (a,) and single.offsets == (0.0,) and single.duration == a.duration


def test_the_timeline_lists_every_run_s_events_by_name_at_timeline_times(runs):
    a, b, _ = runs
    rows = timeline_events([a, b], (1.0, 0.0), ("A", "B"))
    assert [(t, text) for t, text, _ in rows] == [(2.0, "A: go"), (2.0, "B: go"), (3.5, "A: e-stop")]


def test_offsets_keep_the_latest_anchor_at_its_own_time_and_bad_ones_are_refused(runs):
    assert offsets_for([3.0, 0.0, 1.25]) == (0.0, 3.0, 1.75)
    a, b, _ = runs
    for bad in ((1.0,), (-1.0, 0.0), (math.inf, 0.0)):
        with pytest.raises(ValueError, match="one finite offset >= 0 s per recording"):
            Player([a, b], clock=lambda: 0.0, offsets=bad)
    with pytest.raises(ValueError, match="at least one recording"):
        Player([], clock=lambda: 0.0)
