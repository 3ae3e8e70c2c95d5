"""Packing prediction: CVT spacing ≈ 1.07/√λ, λ = N√φ/∫√φ (REFERENCE.md §5)."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from swarmdeck.coverage import (
    GaussianMixture,
    QuadratureOptions,
    bounded_voronoi,
    cell_moments,
    packing_warning,
    predicted_spacing,
)

BOUNDS = (-1.6, 1.6, -1.0, 1.0)


def test_uniform_density_spacing_is_hexagonal():
    n = 50
    s, _ = predicted_spacing(GaussianMixture(1.0), n, BOUNDS)
    assert s == pytest.approx(1.07 * np.sqrt(6.4 / n), rel=1e-9)


def test_prediction_matches_a_computed_cvt():
    g = GaussianMixture(0.005, [[0.0, 0.0]], [0.12], [1.0])
    n = 40
    pred, where = predicted_spacing(g, n, BOUNDS)
    assert np.hypot(*where) < 0.06
    rng = np.random.default_rng(0)
    p = rng.normal(0, 0.4, (n, 2)).clip([-1.5, -0.9], [1.5, 0.9])
    opts = QuadratureOptions(resolution=2.0)
    for _ in range(150):                                      # discrete Lloyd to a CVT
        p = cell_moments(bounded_voronoi(p, BOUNDS), g, opts).centroids
    d, _ = cKDTree(p).query(p, k=2)
    near_peak = np.hypot(*p.T) < 0.25
    actual = d[near_peak, 1].mean()
    assert pred == pytest.approx(actual, rel=0.25)


def test_warning_names_spacing_and_safety_distance():
    g = GaussianMixture(0.005, [[0.3, -0.2]], [0.1], [1.0])
    msg = packing_warning(g, 60, BOUNDS, 0.17)
    assert msg is not None and "0.170" in msg and "60 robots" in msg
    assert packing_warning(g, 3, BOUNDS, 0.17) is None
    assert packing_warning(g, 1, BOUNDS, 0.17) is None
    with pytest.raises(ValueError):
        predicted_spacing(g, 0, BOUNDS)
