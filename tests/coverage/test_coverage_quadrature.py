"""Cell integrals: closed forms, the raster oracle, ∂H/∂p = 2m(p − c), ∂c/∂t by finite differences."""
from __future__ import annotations

import numpy as np
import pytest
import shapely

from swarmdeck.coverage import (
    GaussianMixture,
    QuadratureOptions,
    bounded_voronoi,
    cell_moments,
    moving_density,
    precondition_positions,
    raster_moments,
    s1_density,
)
from swarmdeck.coverage.quadrature import triangle_rule

BOUNDS = (-1.6, 1.6, -1.0, 1.0)
FINE = QuadratureOptions(min_level=3, max_level=3)
THREE = GaussianMixture(0.01, mu=[[0.3, 0.2], [-0.8, -0.4], [1.0, 0.5]], sigma=[0.15, 0.25, 0.3],
                        weight=[1.0, 0.8, 0.6], mu_dot=[[0.1, 0.0], [0.0, 0.2], [-0.1, -0.1]],
                        sigma_dot=[0.01, 0.0, -0.02], weight_dot=[0.1, 0.0, -0.2])


def _robots(rng, n, bounds=BOUNDS):
    p, _ = precondition_positions(rng.uniform(np.array(bounds)[[0, 2]], np.array(bounds)[[1, 3]],
                                              (n, 2)), bounds)
    return p


@pytest.mark.parametrize("level", [0, 1, 2])
def test_triangle_rule_is_exact_to_degree_five(level):
    bary, w = triangle_rule(level)
    assert w.sum() == pytest.approx(1.0, abs=1e-15)
    # ∫_T x^a y^b over the unit triangle (0,0),(1,0),(0,1) = a! b! / (a + b + 2)!
    from math import factorial
    x, y = bary[:, 1], bary[:, 2]
    for a in range(6):
        for b in range(6 - a):
            exact = factorial(a) * factorial(b) / factorial(a + b + 2)
            assert 0.5 * (w * x ** a * y ** b).sum() == pytest.approx(exact, rel=1e-13)


def test_uniform_density_closed_forms(rng):
    g = GaussianMixture(0.7)
    p = _robots(rng, 12)
    vor = bounded_voronoi(p)
    m = cell_moments(vor, g)
    polys = vor.polygons()
    np.testing.assert_allclose(m.masses, 0.7 * m.areas, rtol=1e-13)
    want = np.array([[shapely.Polygon(c).centroid.x, shapely.Polygon(c).centroid.y] for c in polys])
    np.testing.assert_allclose(m.centroids, want, atol=1e-12)
    np.testing.assert_array_equal(m.dc_dt, 0.0)
    # one robot: polar moment of the whole rectangle, H = I + A ‖p − c‖²
    one = cell_moments(bounded_voronoi(np.array([[0.4, -0.3]])), g)
    a, b = 3.2, 2.0
    assert one.polar[0] == pytest.approx(0.7 * a * b * (a * a + b * b) / 12.0, rel=1e-12)
    assert one.cost_H == pytest.approx(one.polar[0] + 0.7 * a * b * 0.25, rel=1e-12)


@pytest.mark.parametrize("density", [THREE, moving_density().at(4.0), s1_density().at(1.0)])
@pytest.mark.parametrize("n", [1, 40])
def test_quadrature_agrees_with_raster_oracle(density, n, rng):
    p = _robots(rng, n)
    quad = cell_moments(bounded_voronoi(p), density)
    ras = raster_moments(p, density, BOUNDS, h=0.005)
    np.testing.assert_allclose(quad.masses, ras.masses, rtol=1e-2, atol=1e-4)
    assert quad.masses.sum() == pytest.approx(ras.masses.sum(), rel=1e-5)
    assert np.abs(quad.centroids - ras.centroids).max() < 4e-3            # O(h) oracle
    assert quad.cost_H == pytest.approx(ras.cost_H, rel=1e-3)
    scale = np.abs(quad.dc_dt).max() + 1e-9
    assert np.abs(quad.dc_dt - ras.dc_dt).max() < 3e-2 * scale + 1e-5


@pytest.mark.parametrize("n", [10, 50, 200])
def test_default_accuracy_of_centroids_is_1e5_m(n, rng):
    p = _robots(rng, n)
    vor = bounded_voronoi(p)
    ref = cell_moments(vor, THREE, QuadratureOptions(resolution=0.3, min_level=1, max_level=6))
    for opts in (QuadratureOptions(resolution=1.25), QuadratureOptions()):
        got = cell_moments(vor, THREE, opts)
        assert np.abs(got.centroids - ref.centroids).max() < 1e-5
        assert got.cost_H == pytest.approx(ref.cost_H, rel=1e-5)
        assert np.abs(got.dc_dt - ref.dc_dt).max() < 1e-3 * np.abs(ref.dc_dt).max()


def test_gradient_of_H_is_2m_p_minus_c(rng):
    p = _robots(rng, 30)
    m = cell_moments(bounded_voronoi(p), THREE, FINE)
    grad = 2.0 * m.masses[:, None] * (p - m.centroids)
    h = 1e-6
    fd = np.zeros_like(p)
    near_wall = np.argsort(np.minimum(np.abs(np.abs(p[:, 0]) - 1.6), np.abs(np.abs(p[:, 1]) - 1.0)))
    check = np.unique(np.concatenate([near_wall[:4], np.arange(0, 30, 7)]))
    for i in check:
        for c in range(2):
            d = np.zeros_like(p)
            d[i, c] = h
            fd[i, c] = (cell_moments(bounded_voronoi(p + d), THREE, FINE).cost_H
                        - cell_moments(bounded_voronoi(p - d), THREE, FINE).cost_H) / (2 * h)
    assert np.abs(fd[check] - grad[check]).max() <= 1e-6 * np.abs(grad).max()


@pytest.mark.parametrize("t", [0.3, 2.1, 9.7])
def test_dc_dt_matches_finite_difference_in_time(t, rng):
    dens = moving_density()
    p = _robots(rng, 20)
    vor = bounded_voronoi(p)
    m = cell_moments(vor, dens.at(t), FINE)
    h = 1e-5
    fd = (cell_moments(vor, dens.at(t + h), FINE).centroids
          - cell_moments(vor, dens.at(t - h), FINE).centroids) / (2 * h)
    assert np.abs(m.dc_dt - fd).max() <= 1e-6 * np.abs(fd).max()
    assert np.abs(m.dm_dt - (cell_moments(vor, dens.at(t + h), FINE).masses
                             - cell_moments(vor, dens.at(t - h), FINE).masses) / (2 * h)).max() < 1e-7


def test_massless_cells_fall_back_to_area_centroid():
    g = GaussianMixture(0.0, mu=[[1.5, 0.9]], sigma=[0.02], weight=[1.0])
    p = np.array([[-1.5, -0.9], [-1.0, -0.9], [1.5, 0.9]])
    m = cell_moments(bounded_voronoi(p), g)
    assert m.massless[0] and m.massless[1] and not m.massless[2]
    assert np.all(np.isfinite(m.centroids)) and np.all(np.isfinite(m.dc_dt))
    assert np.all(m.centroids[:2, 0] < 0)


def test_options_validation():
    with pytest.raises(ValueError):
        QuadratureOptions(resolution=0.0)
    with pytest.raises(ValueError):
        QuadratureOptions(min_level=3, max_level=2)
