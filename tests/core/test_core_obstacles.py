"""Line-segment obstacles (core/obstacles.py): closed-form distances, the spatial query, and every bad input
refused with a message naming the segment."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.core.obstacles import (
    ObstacleError,
    Obstacles,
    point_segment_distance,
    polygon_segments,
    segments_cross,
    segments_near,
)

WALL = [[[-0.5, 0.0], [0.5, 0.0]]]


def test_distance_closed_form_interior_and_ends() -> None:
    pts = np.array([[0.0, 0.3], [0.2, -0.4], [0.8, 0.0], [-0.5, 0.0], [-0.8, 0.4]])
    d = point_segment_distance(pts, WALL)[:, 0]
    np.testing.assert_allclose(d, [0.3, 0.4, 0.3, 0.0, 0.5], atol=1e-15)


def test_distance_to_a_diagonal_segment() -> None:
    seg = [[[0.0, 0.0], [1.0, 1.0]]]
    d = point_segment_distance([[1.0, 0.0], [2.0, 2.0]], seg)[:, 0]
    np.testing.assert_allclose(d, [np.sqrt(0.5), np.sqrt(2.0)], rtol=1e-14)


@settings(max_examples=40)
@given(st.integers(0, 2**31 - 1), st.floats(0.05, 1.0))
def test_spatial_query_equals_the_dense_distances(seed: int, radius: float) -> None:
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-1.5, 1.5, (60, 2))
    seg = rng.uniform(-1.5, 1.5, (7, 2, 2))
    dense = point_segment_distance(pts, seg)
    i, k, d = segments_near(pts, seg, radius)
    want_i, want_k = np.nonzero(dense <= radius)
    np.testing.assert_array_equal(i, want_i)
    np.testing.assert_array_equal(k, want_k)
    np.testing.assert_allclose(d, dense[want_i, want_k], atol=1e-12)


def test_polygon_is_its_closed_chain_of_edges() -> None:
    square = [[0, 0], [1, 0], [1, 1], [0, 1]]
    segs = polygon_segments(square)
    assert segs.shape == (4, 2, 2)
    np.testing.assert_array_equal(segs[-1], [[0, 1], [0, 0]])
    assert polygon_segments(square, closed=False).shape == (3, 2, 2)
    obs = Obstacles.from_polygons([square], segments=WALL)
    assert obs.m == 5


def test_config_list_reads_segments_polygons_and_polylines() -> None:
    obs = Obstacles.from_config([[[0, 0], [0.5, 0]], {"polygon": [[0, 0.2], [0.2, 0.2], [0.1, 0.4]]},
                                 {"polyline": [[-1, 0], [-1, 0.5], [-0.5, 0.5]]}, {"segment": [[1, 1], [1, 0.5]]}])
    assert obs.m == 1 + 3 + 2 + 1
    assert Obstacles.of(obs.to_list()) == obs
    assert hash(Obstacles.of(obs.to_list())) == hash(obs)


def test_segment_crossing() -> None:
    a0 = np.array([[0.0, 0.1], [0.0, 0.1], [0.7, 0.1]])
    a1 = np.array([[0.0, -0.1], [0.0, 0.05], [0.7, -0.1]])
    np.testing.assert_array_equal(segments_cross(a0, a1, np.array(WALL, dtype=float)), [True, False, False])


@pytest.mark.parametrize("bad, words", [
    ([[[0.0, 0.0], [0.0, 0.0]]], "segment 0 has zero length"),
    ([[[0.0, 0.0], [1.0, 0.0]], [[0.2, np.nan], [0.3, 0.0]]], "segment 1 has NaN"),
    ([[[0.0, 0.0], [1.0, 0.0]], [[0.2, np.inf], [0.3, 0.0]]], "segment 1 has NaN or inf"),
    ([[0.0, 0.0], [1.0, 0.0]], "shape (M, 2, 2)"),
    ("walls", "must be"),
])
def test_bad_segments_are_refused_naming_them(bad: object, words: str) -> None:
    with pytest.raises(ObstacleError, match=words.replace("(", r"\(").replace(")", r"\)")):
        Obstacles.of(bad)  # type: ignore[arg-type]


def test_bad_config_entries_are_named() -> None:
    with pytest.raises(ObstacleError, match="entry 1"):
        Obstacles.from_config([[[0, 0], [1, 0]], {"circle": [0, 0]}])
    with pytest.raises(ObstacleError, match=r"entry 0 \(polygon\).*at least 3"):
        Obstacles.from_config([{"polygon": [[0, 0], [1, 0]]}])


def test_outside_the_arena_is_refused_naming_the_segment() -> None:
    obs = Obstacles([[[0.0, 0.0], [1.0, 0.0]], [[1.0, 0.0], [1.7, 0.0]]])
    with pytest.raises(ObstacleError, match=r"segment 1 .*outside the arena"):
        obs.check_inside(DEFAULT_BOUNDS)


def test_crossing_a_start_pose_or_charger_slot_is_refused() -> None:
    obs = Obstacles(WALL)
    with pytest.raises(ObstacleError, match=r"segment 0 .*crosses start pose 1"):
        obs.check_clear([[1.0, 1.0, 0.0], [0.1, 0.05, 0.0]], 0.115, "start pose")
    with pytest.raises(ObstacleError, match="crosses charger slot 0"):
        obs.check_clear([[0.45, -0.02]], 0.115, "charger slot")
    assert obs.check_clear([[0.0, 0.5, 0.0]], 0.115, "start pose") is obs


def test_segments_are_read_only_copies() -> None:
    src = np.array(WALL, dtype=float)
    obs = Obstacles(src)
    src[0, 0, 0] = 9.0
    assert obs.segments[0, 0, 0] == -0.5
    with pytest.raises(ValueError):
        obs.segments[0, 0, 0] = 1.0
