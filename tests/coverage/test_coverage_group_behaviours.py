"""Rendezvous and formation control (paper §V-A, §V-B) and the graphs they run on."""
import numpy as np
import pytest

from swarmdeck.core.graphs import (
    complete_laplacian,
    cycle_laplacian,
    delta_disk_laplacian,
    edges_of,
    line_laplacian,
    random_connected_laplacian,
    rigid_formation,
    topological_neighbors,
)
from swarmdeck.coverage.group import consensus, formation_control, formation_energy, formation_errors
from swarmdeck.devices import Arena, ArenaConfig


def _connected(L):
    return np.sum(np.linalg.eigvalsh(L) < 1e-9) == 1


def test_graph_laplacians():
    for L in (cycle_laplacian(6), line_laplacian(6), complete_laplacian(6), random_connected_laplacian(12, 5, rng=1)):
        np.testing.assert_allclose(L, L.T)
        np.testing.assert_allclose(L.sum(axis=1), 0.0)
        assert _connected(L)
    assert len(edges_of(cycle_laplacian(6))) == 6
    assert len(edges_of(line_laplacian(6))) == 5
    assert len(edges_of(random_connected_laplacian(12, 5, rng=1))) == 11 + 5


def test_neighbour_queries_do_not_mutate():
    L = cycle_laplacian(5)
    keep = L.copy()
    assert topological_neighbors(L, 0).tolist() == [1, 4]
    np.testing.assert_array_equal(L, keep)
    pts = np.array([[0.0, 0.0], [0.3, 0.0], [1.0, 0.0]])
    assert edges_of(delta_disk_laplacian(pts, 0.5)).tolist() == [[0, 1]]


def test_rigid_formation_is_minimally_rigid():
    shape, edges, lengths = rigid_formation(6, 0.4)
    assert len(edges) == 2 * 6 - 3
    np.testing.assert_allclose(formation_errors(shape, edges, lengths), 0.0, atol=1e-15)
    # Rigidity matrix rank 2n - 3 (infinitesimally rigid).
    R = np.zeros((len(edges), 12))
    for k, (i, j) in enumerate(edges):
        d = shape[i] - shape[j]
        R[k, 2 * i:2 * i + 2] = d
        R[k, 2 * j:2 * j + 2] = -d
    assert np.linalg.matrix_rank(R) == 9


def test_formation_gradient_matches_finite_differences(rng):
    _, edges, lengths = rigid_formation(6, 0.4)
    x = rng.uniform(-1, 1, (6, 2))
    u = formation_control(x, edges, lengths, alpha=2.0)
    h = 1e-6
    grad = np.zeros_like(x)
    for i in range(6):
        for k in range(2):
            xp, xm = x.copy(), x.copy()
            xp[i, k] += h
            xm[i, k] -= h
            grad[i, k] = (formation_energy(xp, edges, lengths, 2.0) - formation_energy(xm, edges, lengths, 2.0)) / (2 * h)
    np.testing.assert_allclose(u, -grad, rtol=1e-6, atol=1e-8)


def test_rendezvous_on_c6_converges_to_initial_centroid(rng):
    x = rng.uniform(-1.5, 1.5, (6, 2))
    c0 = x.mean(axis=0)
    L = cycle_laplacian(6)
    for _ in range(3000):
        x = x + 0.033 * consensus(x, L)
    np.testing.assert_allclose(x, np.tile(c0, (6, 1)), atol=1e-6)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rendezvous_example_gathers_safely(seed):
    from swarmdeck.examples.rendezvous import experiment

    arena = Arena(6, duration=30.0, config=ArenaConfig(seed=seed), safety=_safety_or_skip())
    result = experiment(arena)
    # Six robots whose look-ahead points stay 0.17 m apart: the tightest cluster has radius ~0.17 m.
    assert result["cluster radius (m)"] < 0.3
    assert result["centroid drift (m)"] < 0.01
    assert arena.report().validation.steps_with_collision == 0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_formation_example_reaches_distances_within_1cm(seed):
    from swarmdeck.examples.formation import experiment

    arena = Arena(6, duration=40.0, config=ArenaConfig(seed=seed), safety=_safety_or_skip())
    result = experiment(arena)
    assert result["largest edge-length error (m)"] < 0.01
    assert arena.report().validation.steps_with_collision == 0


def _safety_or_skip():
    try:
        import swarmdeck.safety  # noqa: F401
        from swarmdeck.safety import SafetyFilter  # noqa: F401
    except ImportError:
        pytest.skip("swarmdeck.safety is not available yet")
    return True
