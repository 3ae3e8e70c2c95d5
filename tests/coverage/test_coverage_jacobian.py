"""∂c/∂p from edge integrals against central finite differences (≤ 1e-6 relative), walls included."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.coverage import (
    EdgeOptions,
    GaussianMixture,
    QuadratureOptions,
    bounded_voronoi,
    cell_moments,
    centroid_jacobian,
    moving_density,
    precondition_positions,
    s1_density,
)

BOUNDS = (-1.6, 1.6, -1.0, 1.0)


def _fine(n):
    """A fixed subdivision (no level switches between p ± h), finer for big cells."""
    level = 5 if n <= 3 else 4 if n <= 9 else 3
    return QuadratureOptions(min_level=level, max_level=level)

FINE_EDGES = EdgeOptions(nodes=10, resolution=0.5)
ANISO = GaussianMixture(0.05, mu=[[0.2, 0.1], [-0.9, -0.3]], weight=[1.0, 0.6],
                        cov=[[[0.12, 0.05], [0.05, 0.06]], [[0.05, -0.02], [-0.02, 0.09]]])


def _centroids(p, density, bounds=BOUNDS):
    return cell_moments(bounded_voronoi(p, bounds), density, _fine(len(p))).centroids


def _fd_jacobian(p, density, h=1e-6, bounds=BOUNDS):
    n = p.shape[0]
    out = np.zeros((2 * n, 2 * n))
    for k in range(2 * n):
        d = np.zeros(2 * n)
        d[k] = h
        d = d.reshape(-1, 2)
        out[:, k] = ((_centroids(p + d, density, bounds) - _centroids(p - d, density, bounds))
                     / (2 * h)).ravel()
    return out


def _jacobian(p, density, edges=FINE_EDGES, bounds=BOUNDS):
    vor = bounded_voronoi(p, bounds)
    return centroid_jacobian(vor, cell_moments(vor, density, _fine(len(p))), density, edges), vor


CASES = {
    "two": np.array([[-0.4, 0.1], [0.5, -0.2]]),
    "three-collinear": np.array([[-1.0, 0.0], [0.0, 0.0], [1.0, 0.0]]),
    "grid-s1": np.array([[x, y] for x in (-1.0, 0.0, 1.0) for y in (-0.5, 0.0, 0.5)]),
    "on-walls": np.array([[-1.6, 0.3], [1.6, -0.2], [0.1, 1.0], [-0.3, -1.0], [1.6, 1.0],
                          [0.0, 0.0], [-0.7, 0.4], [0.8, -0.5]]),
    "random": np.random.default_rng(7).uniform([-1.6, -1.0], [1.6, 1.0], (12, 2)),
}


DENSITIES = {"s1": s1_density().at(3.0), "moving": moving_density().at(5.0), "aniso": ANISO}


@pytest.mark.parametrize("name, dens", [(c, "s1") for c in CASES] + [
    ("two", "moving"), ("on-walls", "moving"), ("three-collinear", "aniso"), ("random", "aniso")])
def test_jacobian_matches_central_differences(name, dens):
    density = DENSITIES[dens]
    p, _ = precondition_positions(CASES[name], BOUNDS, wall_margin=1e-4)
    jac, vor = _jacobian(p, density)
    fd = _fd_jacobian(p, density)
    err = np.abs(jac.toarray() - fd).max() / np.abs(fd).max()
    assert err <= 1e-6, f"relative error {err:.2e}"


def test_sparsity_is_the_neighbour_graph(rng):
    p, _ = precondition_positions(rng.uniform([-1.6, -1.0], [1.6, 1.0], (40, 2)), BOUNDS)
    jac, vor = _jacobian(p, moving_density().at(1.0), EdgeOptions())
    blocks = np.abs(jac.toarray()).reshape(40, 2, 40, 2).max(axis=(1, 3)) > 0
    want = np.eye(40, dtype=bool)
    want[vor.edge_pairs[:, 0], vor.edge_pairs[:, 1]] = True
    want[vor.edge_pairs[:, 1], vor.edge_pairs[:, 0]] = True
    np.testing.assert_array_equal(blocks, want)


@pytest.mark.parametrize("n", [10, 100])
def test_default_edge_options_are_accurate(n, rng):
    p, _ = precondition_positions(rng.uniform([-1.6, -1.0], [1.6, 1.0], (n, 2)), BOUNDS)
    dens = GaussianMixture(0.01, [[0.3, 0.2], [-0.8, -0.4]], [0.15, 0.3], [1.0, 0.7])
    fine, _ = _jacobian(p, dens, EdgeOptions(nodes=16, resolution=0.25))
    default, _ = _jacobian(p, dens, EdgeOptions())
    assert np.abs((fine - default).toarray()).max() <= 1e-5 * np.abs(fine.toarray()).max()


def test_single_robot_has_zero_jacobian():
    jac, _ = _jacobian(np.array([[0.2, 0.1]]), s1_density().at(0.0))
    assert jac.shape == (2, 2) and jac.nnz == 0


def test_uniform_density_1d_sign_check():
    """Two robots at x = ±0.8 on a uniform arena: moving robot 1 right by ε moves the bisector by
    ε/2 and c_0 by ε/4 (REFERENCE.md sign check), so ∂c_0x/∂p_1x = 1/4."""
    p = np.array([[-0.8, 0.0], [0.8, 0.0]])
    jac, _ = _jacobian(p, GaussianMixture(1.0))
    assert jac.toarray()[0, 2] == pytest.approx(0.25, rel=1e-12)
    assert jac.toarray()[0, 0] == pytest.approx(0.25, rel=1e-12)
