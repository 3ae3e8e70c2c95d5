"""core.bounds.Bounds: the arena rectangle is still a 4-tuple, and knows its width, centre, containment and clip."""
import numpy as np
import pytest

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds, check_bounds


def test_bounds_is_still_a_tuple():
    x0, x1, y0, y1 = DEFAULT_BOUNDS
    assert (x0, x1, y0, y1) == (-1.6, 1.6, -1.0, 1.0)
    assert DEFAULT_BOUNDS == (-1.6, 1.6, -1.0, 1.0)
    assert list(DEFAULT_BOUNDS) == [-1.6, 1.6, -1.0, 1.0]
    assert isinstance(check_bounds([-1, 2, -3, 4]), Bounds)
    assert f"{DEFAULT_BOUNDS}" == repr(DEFAULT_BOUNDS) == "(-1.6, 1.6, -1.0, 1.0)"  # messages quote it as before


def test_geometry_of_the_robotarium_floor():
    b = DEFAULT_BOUNDS
    assert b.width == pytest.approx(3.2) and b.height == pytest.approx(2.0)
    assert b.area == pytest.approx(6.4)
    assert b.centre == (0.0, 0.0)
    assert Bounds(0.0, 4.0, 1.0, 2.0).centre == (2.0, 1.5)


def test_of_accepts_any_four_sequence_and_keeps_a_bounds():
    assert Bounds.of((0, 1, 2, 3)) == Bounds(0, 1, 2, 3)
    assert Bounds.of([0, 1, 2, 3]).width == 1
    assert Bounds.of(DEFAULT_BOUNDS) is DEFAULT_BOUNDS


def test_contains_edges_margin_and_extra_columns():
    b = Bounds(-1.0, 1.0, -0.5, 0.5)
    pts = np.array([[0.0, 0.0, 3.0], [1.0, 0.5, 0.0], [1.01, 0.0, 0.0], [0.0, -0.6, 0.0], [0.95, 0.0, 1.0]])
    assert b.contains(pts).tolist() == [True, True, False, False, True]
    assert b.contains(pts, margin=0.1).tolist() == [True, False, False, False, False]
    assert b.contains(pts[0, :2]).shape == ()


def test_clip_is_a_new_array_and_leaves_heading_alone():
    b = Bounds(-1.0, 1.0, -0.5, 0.5)
    poses = np.array([[2.0, -3.0, 0.7], [0.2, 0.1, -1.0]])
    before = poses.copy()
    out = b.clip(poses, margin=0.1)
    np.testing.assert_array_equal(poses, before)
    np.testing.assert_array_equal(out, [[0.9, -0.4, 0.7], [0.2, 0.1, -1.0]])
    assert b.contains(out, margin=0.1).all()


def test_clip_matches_per_column_np_clip_bit_for_bit():
    rng = np.random.default_rng(3)
    b = Bounds(-1.6, 1.6, -1.0, 1.0)
    p = rng.uniform(-3, 3, (200, 2))
    c = 0.137
    ref = np.column_stack((np.clip(p[:, 0], -1.6 + c, 1.6 - c), np.clip(p[:, 1], -1.0 + c, 1.0 - c)))
    np.testing.assert_array_equal(b.clip(p, c), ref)


def test_shrunk_moves_every_side_in_by_the_margin_bit_for_bit():
    b = Bounds(-1.6, 1.6, -1.0, 1.0)
    inner = b.shrunk(0.3)
    assert isinstance(inner, Bounds)
    assert tuple(inner) == (-1.6 + 0.3, 1.6 - 0.3, -1.0 + 0.3, 1.0 - 0.3)
    assert b.shrunk(-0.1) == (-1.7000000000000002, 1.7000000000000002, -1.1, 1.1)
    assert np.all(b.contains(b.clip(np.array([[5.0, -5.0]]), 0.3), 0.3)) and tuple(b) == (-1.6, 1.6, -1.0, 1.0)
