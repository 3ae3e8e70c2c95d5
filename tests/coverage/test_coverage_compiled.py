"""The compiled coverage sums (coverage/kernels.py) give today's numpy results bit for bit.

Random scenes (robots, floor, moving/growing/fading anisotropic bumps, several laws): one coverage tick
with the compiled kernels equals the same tick on the numpy paths in every bit of the commands, the
cell moments and the Jacobian.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core import compiled as core_compiled
from swarmdeck.coverage import CoverageConfig, GaussianMixture, coverage_tick, kernels

BOUNDS = (-1.6, 1.6, -1.0, 1.0)


def test_the_kernels_are_compiled() -> None:
    assert core_compiled.AVAILABLE and kernels.AVAILABLE
    assert hasattr(kernels._cell_sums_compiled, "py_func") and hasattr(kernels._edge_blocks_compiled, "py_func")


def _density(seed: int, k: int, anisotropic: bool) -> GaussianMixture:
    rng = np.random.default_rng(seed)
    mu = rng.uniform([-1.8, -1.2], [1.8, 1.2], (k, 2))
    common = dict(floor=float(rng.choice([0.0, 0.05, 1.0])) if k else 0.5, mu=mu, weight=rng.uniform(0.1, 3.0, k),
                  mu_dot=rng.normal(0.0, 0.2, (k, 2)), weight_dot=rng.normal(0.0, 0.3, k))
    if anisotropic:
        a = rng.normal(0.0, 0.3, (k, 2, 2))
        cov = a @ np.transpose(a, (0, 2, 1)) + 0.01 * np.eye(2)
        return GaussianMixture(cov=cov, **common)
    return GaussianMixture(sigma=rng.uniform(0.05, 0.6, k), sigma_dot=rng.normal(0.0, 0.02, k), **common)


def _tick(p: np.ndarray, density: GaussianMixture, law: str):
    u, state, jac = coverage_tick(p, density, CoverageConfig(law=law, bounds=BOUNDS), t=0.3)
    return u, state, jac


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 200), k=st.integers(0, 12), anisotropic=st.booleans(),
       law=st.sampled_from(["lloyd-ff", "tvd-d1", "tvd-d3"]))
def test_compiled_tick_equals_the_numpy_tick_bit_for_bit(seed: int, n: int, k: int, anisotropic: bool, law: str) -> None:
    rng = np.random.default_rng(seed)
    p = rng.uniform([-1.6, -1.0], [1.6, 1.0], (n, 2))
    density = _density(seed, k, anisotropic)
    u1, s1, j1 = _tick(p, density, law)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(kernels, "AVAILABLE", False)
        u0, s0, j0 = _tick(p, density, law)
    assert s1.status == s0.status
    np.testing.assert_array_equal(u1, u0)
    np.testing.assert_array_equal(s1.centroids, s0.centroids)
    np.testing.assert_array_equal(s1.masses, s0.masses)
    np.testing.assert_array_equal(s1.cost_H, s0.cost_H)
    assert (j1 is None) == (j0 is None)
    if j1 is not None:
        np.testing.assert_array_equal(j1.indptr, j0.indptr)
        np.testing.assert_array_equal(j1.indices, j0.indices)
        np.testing.assert_array_equal(j1.data, j0.data)
