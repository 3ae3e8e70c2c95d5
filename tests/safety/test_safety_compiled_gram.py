"""The compiled Gram assembly (``safety.compiled.gram_dense``) equals A J Aᵀ formed densely."""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.safety.compiled import gram_dense


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), n=st.integers(1, 30), w=st.integers(1, 60), use_j=st.booleans())
def test_gram_equals_the_dense_product(seed: int, n: int, w: int, use_j: bool) -> None:
    rng = np.random.default_rng(seed)
    ai = rng.integers(0, n, w)
    aj = rng.integers(0, n, w)
    aci = rng.normal(size=(w, 2))
    acj = rng.normal(size=(w, 2))
    single = rng.random(w) < 0.3  # single-robot rows: cj = 0, aj = ai
    acj[single] = 0.0
    aj[single] = ai[single]
    M = rng.normal(size=(n, 2, 2))
    J = M @ np.transpose(M, (0, 2, 1))  # symmetric blocks, like the projection's Jacobian
    A = np.zeros((w, n, 2))
    A[np.arange(w), ai] += aci
    A[np.arange(w), aj] += acj
    B = np.einsum("wnd,nde->wne", A, J) if use_j else A
    expect = B.reshape(w, 2 * n) @ A.reshape(w, 2 * n).T
    got = gram_dense(ai, aj, aci, acj, J if use_j else np.zeros((n, 2, 2)), use_j)
    np.testing.assert_allclose(got, expect, rtol=1e-12, atol=1e-12)
