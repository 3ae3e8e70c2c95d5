"""The all-pairs geometry of a few robots gives the k-d tree's answers, bit for bit (issue 28: lean rps runs).

Up to ``DENSE_PAIRS_ROBOTS`` robots, :func:`pairs_within`, :func:`nearest_pair_distance` and
:func:`segments_near` compare every pair instead of building a k-d tree (no scipy import for an rps-sized run).
Each is checked against the k-d tree path of the same function: the same points plus far-away points (more than
the dense limit, so the tree path runs), which add no pair within reach and leave the first indices unchanged.
Points on a lattice whose spacing is the radius put pairs exactly on the boundary.
"""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core.graphs import DENSE_PAIRS_ROBOTS, nearest_pair_distance, pairs_within
from swarmdeck.core.obstacles import segments_near

_coord = st.floats(-1.6, 1.6, allow_nan=False, width=64)


@st.composite
def _points(draw: st.DrawFn) -> tuple[np.ndarray, float]:
    """(N, 2) points, N in 2..DENSE_PAIRS_ROBOTS, and a radius (m); half of them on a lattice of that spacing."""
    n = draw(st.integers(2, DENSE_PAIRS_ROBOTS))
    radius = draw(st.floats(0.01, 1.0, allow_nan=False))
    if draw(st.booleans()):
        cells = draw(st.lists(st.tuples(st.integers(-3, 3), st.integers(-3, 3)), min_size=n, max_size=n))
        step = radius * draw(st.sampled_from([1.0, 0.5, 1.0 / 3.0]))
        return np.asarray(cells, dtype=float) * step + draw(_coord), radius
    return np.asarray(draw(st.lists(st.tuples(_coord, _coord), min_size=n, max_size=n)), dtype=float), radius


def _with_far(points: np.ndarray, reach: float) -> np.ndarray:
    """``points`` and DENSE_PAIRS_ROBOTS far-away points, each farther than ``reach`` from every other point."""
    far = 1000.0 + 10.0 * (reach + 1.0) * np.arange(1, DENSE_PAIRS_ROBOTS + 1)
    return np.vstack([points, np.column_stack([far, np.full_like(far, 1000.0)])])


@settings(max_examples=100, deadline=None)
@given(_points())
def test_pairs_within_dense_equals_the_tree(case: tuple[np.ndarray, float]) -> None:
    points, radius = case
    dense = pairs_within(points, radius)
    tree = pairs_within(_with_far(points, radius), radius)
    assert dense.dtype == tree.dtype == np.intp
    np.testing.assert_array_equal(dense, tree)


def test_pairs_within_keeps_a_pair_exactly_at_the_radius() -> None:
    points = np.array([[0.0, 0.0], [0.3, 0.4], [5.0, 5.0]])
    np.testing.assert_array_equal(pairs_within(points, 0.5), [[0, 1]])
    np.testing.assert_array_equal(pairs_within(_with_far(points, 0.5), 0.5), [[0, 1]])
    assert pairs_within(points, float(np.nextafter(0.5, 0.0))).shape == (0, 2)


@settings(max_examples=100, deadline=None)
@given(_points())
def test_nearest_pair_distance_dense_equals_the_tree(case: tuple[np.ndarray, float]) -> None:
    points, _ = case
    from scipy.spatial import cKDTree

    assert nearest_pair_distance(points) == float(cKDTree(points).query(points, k=2)[0][:, 1].min())


@settings(max_examples=100, deadline=None)
@given(_points(), st.lists(st.tuples(_coord, _coord, _coord, _coord), min_size=1, max_size=6))
def test_segments_near_dense_equals_the_tree(case: tuple[np.ndarray, float], ends: list) -> None:
    points, radius = case
    segments = np.asarray(ends, dtype=float).reshape(-1, 2, 2)
    i, k, d = segments_near(points, segments, radius)
    ti, tk, td = segments_near(_with_far(points, radius + 10.0), segments, radius)
    np.testing.assert_array_equal(i, ti)
    np.testing.assert_array_equal(k, tk)
    np.testing.assert_array_equal(d, td)  # the same bits
