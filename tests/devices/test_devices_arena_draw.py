"""An experiment draws on the arena through ``arena.draw`` (issue 29 item 3): points, lines, polylines, circles,
polygons and text in arena metres, with colour and lifetime (ticks or seconds, a key to replace, clear);
each step's drawing is ``arena.last_annotations`` (what its Frame carries); cap hits are counted and are events."""
import numpy as np
import pytest

from swarmdeck.core.annotations import CIRCLE, POINT, POLYGON, POLYLINE, TEXT
from swarmdeck.core.annotator import parse_color
from swarmdeck.devices import Arena


@pytest.fixture
def arena():
    return Arena(3, initial_conditions=np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]))


def test_every_primitive_with_its_colour_and_size(arena):
    d = arena.draw
    d.points([[0.1, 0.2], [0.3, 0.4]], radius=0.02, color="#ff000080")
    d.line((0, 0), (1, 1), color="g", width=0.02)
    d.polyline([[0, 0], [0.5, 0], [0.5, 0.5]], color=(0, 0, 255))
    d.circle((0.2, -0.3), 0.15, color=(0.0, 1.0, 0.0), fill=True, alpha=0.5)
    d.polygon([[-1, -0.5], [-0.5, -0.5], [-0.75, 0.0]], color="purple")
    d.text((0.0, 0.8), "hello", height=0.08, color="black")
    arena.step()
    a = arena.last_annotations
    assert a.kinds.tolist() == [POINT, POINT, POLYLINE, POLYLINE, CIRCLE, POLYGON, TEXT]
    assert a.vertex_counts().tolist() == [1, 1, 2, 3, 1, 3, 1]
    assert a.anchors()[4].tolist() == [0.2, -0.3] and a.sizes[4] == 0.15 and a.filled[4]
    assert a.colors[0].tolist() == [255, 0, 0, 128] and a.colors[3].tolist() == [0, 0, 255, 255]
    assert a.colors[4].tolist() == [0, 255, 0, 128]
    assert a.texts[6] == "hello" and a.sizes[6] == 0.08


def test_lifetimes_in_ticks_and_seconds_keys_and_clear(arena):
    d = arena.draw
    d.point((0, 0), ticks=2)
    d.circle((0, 0), 0.1, seconds=0.1)  # three 0.033 s steps: t = 0.033, 0.066, 0.099
    d.text((0, 0), "stays")
    counts = []
    for _ in range(5):
        arena.step()
        counts.append(arena.last_annotations.kinds.tolist())
    assert counts[0] == [POINT, CIRCLE, TEXT] and counts[1] == [POINT, CIRCLE, TEXT]
    assert counts[2] == [CIRCLE, TEXT] and counts[3] == [TEXT] and counts[4] == [TEXT]
    for k in range(3):  # the same key replaces: one marker that moves, not three
        d.point((0.1 * k, 0), key="marker")
        arena.step()
    assert arena.last_annotations.kinds.tolist() == [TEXT, POINT]
    assert arena.last_annotations.anchors()[1].tolist() == pytest.approx([0.2, 0.0])
    d.remove("marker")
    arena.step()
    assert arena.last_annotations.kinds.tolist() == [TEXT]
    d.clear()
    arena.step()
    assert len(arena.last_annotations) == 0


def test_caps_hit_are_counted_and_become_events_without_stopping_the_run(arena):
    d = arena.draw
    d.points(np.random.default_rng(0).uniform(-1, 1, (1_000_000, 2)), ticks=1)
    d.text((0, 0), "y" * 10_000_000, ticks=1)  # over the alive cap: dropped too
    d.line((0, 0), (np.nan, 1.0), ticks=1)
    arena.step()
    assert len(arena.last_annotations) == 4096
    assert d.warnings == 1  # one tick, one kind of hit: 1e6 - 4096 points, the text and the line over the cap
    assert any("over the cap of 4096" in e for e in arena.events)
    d.line((0, 0), (np.nan, 1.0), ticks=1)
    d.circle((5.0, 0.0), 100.0, ticks=1)
    arena.step()
    assert arena.last_annotations.kinds.tolist() == [CIRCLE]
    assert arena.last_annotations.anchors()[0].tolist() == [1.6, 0.0]
    assert any("NaN/inf" in e for e in arena.events) and any("arena diagonal" in e for e in arena.events)


def test_bad_arguments_name_what_is_wrong(arena):
    with pytest.raises(ValueError, match="unknown colour 'mauvish'"):
        arena.draw.point((0, 0), color="mauvish")
    with pytest.raises(ValueError, match="a polygon needs at least 3 vertices"):
        arena.draw.polygon([[0, 0], [1, 1]])
    with pytest.raises(ValueError, match="ticks must be a positive integer"):
        arena.draw.point((0, 0), ticks=0)
    with pytest.raises(ValueError, match=r"points must be \(x, y\)"):
        arena.draw.points(np.zeros((3, 3)))
    assert parse_color("#abc").tolist() == [170, 187, 204, 255]
    assert parse_color((10, 20, 30)).tolist() == [10, 20, 30, 255]
    assert parse_color((0.5, 0.5, 0.5, 1.0)).tolist() == [128, 128, 128, 255]


def test_each_robots_pen_keeps_its_own_keys(arena):
    from swarmdeck.core.annotator import robot_drawing

    pens = [robot_drawing(arena.draw, i) for i in range(3)]
    for i, pen in enumerate(pens):
        pen.point((0.1 * i, 0.0), key="me")
    pens[1].point((0.5, 0.5), key="me")  # replaces robot 1's only
    arena.step()
    assert sorted(map(tuple, arena.last_annotations.anchors().tolist())) == [(0.0, 0.0), (0.2, 0.0), (0.5, 0.5)]
    pens[0].clear()
    arena.step()
    assert len(arena.last_annotations) == 2
    with pytest.raises(AttributeError, match="not 'collect'"):
        pens[2].collect(0.0)


def test_a_cap_hit_every_step_is_counted_every_step_and_said_once_a_second(arena):
    for _ in range(60):  # 60 steps of 0.033 s: about 2 s of run time
        arena.draw.circle((0.0, 0.0), 1e3, ticks=1)  # clipped every step
        arena.step()
    said = [e for e in arena.events if "arena diagonal" in e]
    assert arena.draw.warnings == 60
    assert 2 <= len(said) <= 3
