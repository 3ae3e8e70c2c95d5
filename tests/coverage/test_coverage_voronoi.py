"""Bounded Voronoi: areas, adjacency and polygons, incl. degenerate inputs, against shapely."""
from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.coverage import bounded_voronoi, precondition_positions

BOUNDS = (-1.6, 1.6, -1.0, 1.0)
AREA = 3.2 * 2.0


def _shapely_areas(p, bounds=BOUNDS):
    box = shapely.box(bounds[0], bounds[2], bounds[1], bounds[3])
    polys = shapely.voronoi_polygons(shapely.MultiPoint(p), extend_to=box, ordered=True)
    return np.array([g.intersection(box).area for g in polys.geoms])


def _check_diagram(p, bounds=BOUNDS):
    vor = bounded_voronoi(p, bounds)
    area = (bounds[1] - bounds[0]) * (bounds[3] - bounds[2])
    areas = vor.areas()
    assert areas.sum() == pytest.approx(area, rel=1e-12)
    assert np.all(areas > 0)
    polys = vor.polygons()
    assert len(polys) == len(p)
    for i, poly in enumerate(polys):
        assert poly.shape[0] >= 3
        # counter-clockwise, convex, containing the robot, inside the rectangle
        e = np.roll(poly, -1, axis=0) - poly
        r = p[i] - poly
        assert np.all(e[:, 0] * r[:, 1] - e[:, 1] * r[:, 0] > -1e-12)
        assert shapely.Polygon(poly).area == pytest.approx(areas[i], rel=1e-9, abs=1e-15)
        assert np.all(poly >= np.array(bounds)[[0, 2]] - 1e-12)
        assert np.all(poly <= np.array(bounds)[[1, 3]] + 1e-12)
    # every shared edge lies on the bisector of its two robots
    seg = vor.edge_segments()
    i, j = vor.edge_pairs.T
    for end in (0, 1):
        q = seg[:, end]
        di = np.hypot(*(q - p[i]).T)
        dj = np.hypot(*(q - p[j]).T)
        np.testing.assert_allclose(di, dj, rtol=1e-9, atol=1e-12)
    assert np.all(i < j)
    assert len({tuple(e) for e in vor.edge_pairs.tolist()}) == len(i)
    return vor


@settings(max_examples=40, deadline=None)
@given(n=st.integers(1, 60), seed=st.integers(0, 2**31))
def test_random_diagrams_match_shapely(n, seed):
    rng = np.random.default_rng(seed)
    p, _ = precondition_positions(rng.uniform([-1.6, -1.0], [1.6, 1.0], (n, 2)), BOUNDS)
    vor = _check_diagram(p)
    np.testing.assert_allclose(vor.areas(), _shapely_areas(p), rtol=1e-9, atol=1e-12)


def test_many_robots_on_a_larger_arena(rng):
    bounds = (-5.0, 5.0, -3.0, 3.0)
    p, _ = precondition_positions(rng.uniform([-5, -3], [5, 3], (800, 2)), bounds)
    vor = _check_diagram(p, bounds)
    np.testing.assert_allclose(vor.areas(), _shapely_areas(p, bounds), rtol=1e-8, atol=1e-12)


@pytest.mark.parametrize("points", [
    [[0.0, 0.0]],
    [[0.3, 0.2], [-0.5, 0.1]],
    [[-1.0, 0.0], [-0.5, 0.0], [0.0, 0.0], [0.5, 0.0], [1.0, 0.0]],          # collinear
    [[x, x * 0.5] for x in np.linspace(-1.4, 1.4, 7)],                      # collinear, diagonal
    [[x, y] for x in (-1.0, 0.0, 1.0) for y in (-0.5, 0.0, 0.5)],           # grid: co-circular
    [[0.5, 0.0], [-0.5, 0.0], [0.0, 0.5], [0.0, -0.5], [0.0, 0.0]],          # 4 co-circular + centre
])
def test_degenerate_but_valid_inputs(points):
    p = np.array(points, dtype=float)
    _check_diagram(p)
    np.testing.assert_allclose(bounded_voronoi(p).areas(), _shapely_areas(p), rtol=1e-9)


def test_grid_neighbours_are_the_grid_edges():
    p = np.array([[x, y] for x in (-1.0, 0.0, 1.0) for y in (-0.5, 0.0, 0.5)])
    vor = bounded_voronoi(p)
    ix, iy = np.divmod(np.arange(9), 3)
    want = [(a, b) for a in range(9) for b in range(a + 1, 9)
            if abs(ix[a] - ix[b]) + abs(iy[a] - iy[b]) == 1]
    assert sorted(map(tuple, vor.edge_pairs.tolist())) == want
    np.testing.assert_array_equal(vor.neighbours_of(4), [1, 3, 5, 7])


def test_robot_on_wall_and_corner_are_clamped_inside():
    raw = np.array([[1.6, 0.0], [-1.6, 1.0], [0.0, -1.0], [0.2, 0.3], [3.0, 5.0]])
    p, moved = precondition_positions(raw, BOUNDS, wall_margin=1e-6)
    assert moved == 4
    assert np.all(p[:, 0] < 1.6) and np.all(p[:, 0] > -1.6)
    assert np.all(p[:, 1] < 1.0) and np.all(p[:, 1] > -1.0)
    np.testing.assert_array_equal(p[3], raw[3])
    _check_diagram(p)
    with pytest.raises(ValueError, match="strictly inside"):
        bounded_voronoi(raw)


def test_duplicates_and_near_duplicates_are_separated():
    raw = np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.5, 0.5], [0.5, 0.5 + 1e-9],
                    [1.6, 1.0], [1.6, 1.0]])
    p, moved = precondition_positions(raw, BOUNDS, min_separation=1e-3)
    assert moved >= 6
    d = np.hypot(*(p[:, None] - p[None]).transpose(2, 0, 1))
    assert d[np.triu_indices(len(p), 1)].min() >= 1e-3 * 0.999
    assert np.abs(p - raw).max() < 5e-3
    _check_diagram(p)
    # deterministic
    np.testing.assert_array_equal(precondition_positions(raw, BOUNDS)[0], p)


@pytest.mark.parametrize("bad", [np.zeros((0, 2)), np.zeros((3, 3)), [[0.0, float("nan")]],
                                 [[float("inf"), 0.0]]])
def test_bad_positions_raise(bad):
    with pytest.raises(ValueError, match="positions"):
        precondition_positions(bad, BOUNDS)


def test_bad_bounds_raise():
    with pytest.raises(ValueError, match="bounds"):
        precondition_positions([[0, 0]], (1.0, -1.0, 0.0, 1.0))


@pytest.mark.parametrize("centre, spread", [((0.0, 0.0), 0.05), ((1.5, 0.9), 0.05),
                                            ((-1.0, 0.0), 0.3), ((0.0, -0.95), 0.02)])
def test_clusters_far_from_walls_get_the_reflections_they_need(centre, spread):
    """Robots bunched together: the first guess of which robots to reflect is wrong for them."""
    rng = np.random.default_rng(5)
    raw = np.array(centre) + rng.normal(0.0, spread, (40, 2))
    p, _ = precondition_positions(raw, BOUNDS)
    vor = _check_diagram(p)
    np.testing.assert_allclose(vor.areas(), _shapely_areas(p), rtol=1e-9, atol=1e-12)
