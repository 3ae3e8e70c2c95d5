"""A zero-length segment (a point) is at its end point's distance from every robot, never NaN, and no warning.

Configs refuse zero-length obstacles, but the geometry is public (core.obstacles) and a point must still stop a
robot: before the fix 0/0 made its distance NaN, so `segments_near` dropped it (NaN <= radius is False)."""
from __future__ import annotations

import warnings

import numpy as np

from swarmdeck.core.obstacles import nearest_points, point_segment_distance, segments_near


def test_nearest_point_of_a_zero_length_segment_is_its_end() -> None:
    seg = np.array([[[0.5, 0.2], [0.5, 0.2]], [[0.0, 0.0], [1.0, 0.0]]])
    pts = np.array([[0.8, 0.6], [0.3, 0.4]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        near = nearest_points(pts, seg)
        dense = point_segment_distance(pts, seg)
    np.testing.assert_array_equal(near, [[0.5, 0.2], [0.3, 0.0]])
    np.testing.assert_allclose(dense[:, 0], np.hypot(pts[:, 0] - 0.5, pts[:, 1] - 0.2))
    np.testing.assert_allclose(dense[:, 1], [0.6, 0.4])


def test_segments_near_finds_a_point_obstacle_for_few_and_many_robots() -> None:
    point = np.array([[[0.0, 0.0], [0.0, 0.0]]])
    for n in (3, 40):  # the all-pairs form and the k-d tree form
        pts = np.column_stack((np.linspace(-2.0, 2.0, n), np.zeros(n)))
        pts[0] = [0.05, 0.0]
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            i, k, d = segments_near(pts, point, 0.1)
        assert 0 in i.tolist(), n
        assert np.isfinite(d).all()
        np.testing.assert_allclose(d[i == 0], [0.05])
