"""What an experiment draws is capped on the trusted side (issue 29 item 3, "bad input"): NaN coordinates are
refused, coordinates outside the arena and huge radii are clipped, 10 MB of text is cut, a million primitives in
a tick are capped — each change counted and described with the cap it hit, never a stall."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core.annotations import (
    CIRCLE,
    POINT,
    POLYGON,
    POLYLINE,
    TEXT,
    AnnotationLimits,
    Annotations,
    sanitize,
)
from swarmdeck.core.bounds import DEFAULT_BOUNDS

B = DEFAULT_BOUNDS  # (-1.6, 1.6, -1, 1)


def batch(kinds, vertices, counts, sizes=None, texts=None):
    p = len(kinds)
    return Annotations(kinds=np.asarray(kinds), offsets=np.concatenate(([0], np.cumsum(counts))),
                       vertices=np.asarray(vertices, dtype=float).reshape(-1, 2),
                       sizes=np.full(p, 0.05) if sizes is None else sizes, colors=np.full((p, 4), 255),
                       filled=np.zeros(p, dtype=bool), texts=tuple(texts or [""] * p))


def test_nan_coordinates_and_sizes_are_refused_and_counted():
    a = batch([POINT, POLYLINE, CIRCLE, CIRCLE], [[0, 0], [0, 0], [math.nan, 1], [0.1, 0.1], [0.2, 0.2]],
              [1, 2, 1, 1], sizes=np.array([0.01, 0.01, math.inf, -1.0]))
    out, report = sanitize(a, B)
    assert len(out) == 1 and out.kinds.tolist() == [POINT]
    assert report.non_finite == 3 and report.given == 4 and report.kept == 1
    assert any("NaN/inf" in m for m in report.messages())


def test_a_huge_radius_is_clipped_to_the_arena_diagonal_and_coordinates_into_the_arena():
    a = batch([CIRCLE, POLYLINE], [[0, 0], [-100, 0], [100, 5]], [1, 2], sizes=np.array([1e9, 0.01]))
    out, report = sanitize(a, B)
    assert out.sizes[0] == pytest.approx(math.hypot(3.2, 2.0))
    assert out.vertices[1:].tolist() == [[-1.6, 0.0], [1.6, 1.0]]
    assert (report.clipped_size, report.clipped_to_arena) == (1, 1)
    assert any("arena diagonal" in m for m in report.messages())


def test_ten_megabytes_of_text_are_cut_to_the_cap():
    a = batch([TEXT], [[0, 0]], [1], texts=["x" * 10_000_000 + "\x00"])
    out, report = sanitize(a, B)
    assert len(out.texts[0]) == 200 and out.texts[0].endswith("…")
    assert report.cut_text == 1 and "200 characters" in " ".join(report.messages())


def test_control_characters_become_spaces():
    out, _ = sanitize(batch([TEXT], [[0, 0]], [1], texts=["a\nb\x1b[2Jc"]), B)
    assert out.texts[0] == "a b [2Jc"


def test_a_million_primitives_are_capped_not_a_stall():
    n = 1_000_000  # (bench/bench_annotations.py measures how fast: milliseconds)
    a = batch(np.full(n, POINT), np.zeros((n, 2)), np.ones(n, dtype=np.int64), sizes=np.full(n, 0.01))
    out, report = sanitize(a, B)
    assert len(out) == 4096 and report.over_primitives == n - 4096
    assert "4096 per tick" in " ".join(report.messages())


def test_vertices_and_total_text_caps():
    limits = AnnotationLimits(max_vertices=10, max_total_text=5)
    a = batch([POLYLINE, POLYLINE, TEXT, TEXT], np.zeros((10, 2)), [4, 4, 1, 1], texts=["", "", "abc", "def"])
    out, report = sanitize(a, B, limits)
    assert out.kinds.tolist() == [POLYLINE, POLYLINE, TEXT]  # 4 + 4 + 1 vertices fit; the second text's 3 chars do not
    assert (report.over_vertices, report.over_text) == (0, 1)
    out, report = sanitize(batch([POLYGON, POLYGON], np.zeros((12, 2)), [6, 6]), B, limits)
    assert len(out) == 1 and report.over_vertices == 1


def test_malformed_structure_is_refused_with_what_is_wrong():
    with pytest.raises(ValueError, match="primitive 0 \\(polygon\\) has 2 vertices"):
        batch([POLYGON], np.zeros((2, 2)), [2])
    with pytest.raises(ValueError, match="offsets"):
        Annotations(kinds=[POINT], offsets=[0, 5], vertices=np.zeros((1, 2)), sizes=[0.1], colors=[[0, 0, 0, 255]],
                    filled=[False], texts=("",))
    with pytest.raises(ValueError, match="kinds must be integers"):
        batch([9], np.zeros((1, 2)), [1])


coords = st.floats(allow_nan=True, allow_infinity=True, width=32)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.sampled_from([POINT, POLYLINE, CIRCLE, POLYGON, TEXT]), st.integers(0, 3),
                          st.lists(st.tuples(coords, coords), min_size=3, max_size=5), coords, st.text(max_size=300)),
                max_size=30))
def test_whatever_comes_in_what_goes_out_is_finite_inside_the_arena_and_within_the_caps(prims):
    kinds, verts, counts, sizes, texts = [], [], [], [], []
    for kind, _, pts, size, text in prims:
        k = {POINT: 1, CIRCLE: 1, TEXT: 1, POLYLINE: 2, POLYGON: 3}[kind]
        kinds.append(kind)
        verts.extend(pts[:k])
        counts.append(k)
        sizes.append(size)
        texts.append(text if kind == TEXT else "")
    limits = AnnotationLimits(max_primitives=20, max_vertices=40, max_text=50, max_total_text=100)
    a = batch(kinds, np.asarray(verts, dtype=float).reshape(-1, 2), np.asarray(counts, dtype=np.int64),
              np.asarray(sizes, dtype=float), texts)
    out, report = sanitize(a, B, limits)
    assert np.isfinite(out.vertices).all() and np.isfinite(out.sizes).all()
    assert (out.vertices[:, 0] >= B.x_min).all() and (out.vertices[:, 0] <= B.x_max).all()
    assert (out.vertices[:, 1] >= B.y_min).all() and (out.vertices[:, 1] <= B.y_max).all()
    assert (out.sizes >= 0).all() and (out.sizes <= math.hypot(3.2, 2.0)).all()
    assert len(out) <= 20 and len(out.vertices) <= 40 and sum(map(len, out.texts)) <= 100
    assert all(len(t) <= 50 and t.isprintable() for t in out.texts)
    assert report.kept == len(out) and report.given == len(a)
