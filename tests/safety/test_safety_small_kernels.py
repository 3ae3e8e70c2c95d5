"""The barrier's plain-Python kernels (safety/small_kernels.py) return the compiled kernels' numbers, bit for bit.

Small problems (at most SMALL_ROBOTS robots: every rps 2.x script) run the dual ascent and the Gram assembly in
plain Python so the process never imports numba; the barrier's answers must not change by a bit for it. Random
problems (robots, rows, coefficients, bounds, warm multipliers, speed limit or none, sweep caps) against numba's.
"""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.safety import compiled, dual_ascent, small_kernels


def _rows(seed: int, n: int, m: int) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(seed)
    ri = rng.integers(0, n, m).astype(np.int64)
    rj = rng.integers(0, n, m).astype(np.int64)
    ci = rng.normal(0.0, 1.0, (m, 2))
    cj = rng.normal(0.0, 1.0, (m, 2))
    single = rng.random(m) < 0.3  # single-robot rows (walls): cj = 0 on the same robot
    rj[single] = ri[single]
    cj[single] = 0.0
    return ri, rj, ci, cj


def _same(a: object, b: object) -> bool:
    return bool(np.array_equal(np.asarray(a), np.asarray(b))) and np.asarray(a).dtype == np.asarray(b).dtype


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, small_kernels.SMALL_ROBOTS), m=st.integers(1, 40),
       capped=st.booleans(), warm=st.booleans(), max_sweeps=st.integers(1, 80))
def test_dual_ascent_same_bits(seed: int, n: int, m: int, capped: bool, warm: bool, max_sweeps: int) -> None:
    rng = np.random.default_rng(seed + 1)
    ri, rj, ci, cj = _rows(seed, n, m)
    b = rng.normal(0.0, 0.1, m)
    nominal = rng.normal(0.0, 0.2, (n, 2))
    lam0 = np.where(rng.random(m) < 0.5, rng.exponential(0.1, m), 0.0) if warm else np.zeros(m)
    vmax = 0.2 if capped else np.inf
    args = (ri, rj, ci, cj, b, nominal, vmax, lam0, max_sweeps, 1e-5, dual_ascent.OMEGA, dual_ascent.RESTRICT_SLACK,
            dual_ascent.FULL_EVERY)
    lam_c, u_c, sweeps_c, worst_c = dual_ascent._ascend(*args)
    lam_p, u_p, sweeps_p, worst_p = small_kernels.ascend(*args)
    assert _same(lam_c, lam_p) and _same(u_c, u_p)
    assert sweeps_c == sweeps_p and float(worst_c) == float(worst_p)
    assert not np.shares_memory(lam_p, lam0)  # the caller's warm multipliers are not written


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, small_kernels.SMALL_ROBOTS), w=st.integers(1, 40),
       use_j=st.booleans())
def test_gram_same_bits(seed: int, n: int, w: int, use_j: bool) -> None:
    ai, aj, aci, acj = _rows(seed, n, w)
    a = np.random.default_rng(seed + 2).normal(0.0, 1.0, (n, 2, 2))
    J = a + np.transpose(a, (0, 2, 1)) if use_j else np.zeros((n, 2, 2))
    assert _same(compiled.gram_dense(ai, aj, aci, acj, J, use_j), small_kernels.gram_dense(ai, aj, aci, acj, J, use_j))


def test_small_is_the_robot_count_before_numba_is_imported() -> None:
    compiled.warm_up_gram()  # numba imported (as in any process that has used a compiled kernel)
    assert not small_kernels.small(1) and not small_kernels.small(small_kernels.SMALL_ROBOTS + 1)
