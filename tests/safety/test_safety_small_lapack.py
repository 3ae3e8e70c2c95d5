"""The active set's Cholesky solve without importing scipy.linalg gives scipy.linalg's bits (issue 28: lean runs).

:func:`swarmdeck.safety.small_lapack.cho_solve` calls LAPACK's dpotrf/dpotrs of scipy's own ``_flapack`` module, as
``scipy.linalg.cho_factor``/``cho_solve`` do: checked bit for bit against them on Gram matrices of random rows (the
active set's systems, ridge added), one and several right-hand sides, and the same refusal of a matrix that is not
positive definite. In a fresh interpreter it loads without ``scipy.linalg``, and scipy.linalg imported after it
still works and agrees.
"""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
import scipy.linalg as sla
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.safety.small_lapack import cho_solve


@settings(max_examples=80, deadline=None)
@given(st.integers(1, 40), st.integers(0, 3), st.integers(0, 2**32 - 1), st.booleans())
def test_the_same_bits_as_scipy_linalg(w: int, k: int, seed: int, dependent: bool) -> None:
    rng = np.random.default_rng(seed)
    rows = rng.normal(size=(w, 2 * max(1, w // 2 + 1)))
    if dependent and w > 1:
        rows[-1] = rows[0] * 0.5  # nearly dependent rows: a badly conditioned Gram matrix
    G = rows @ rows.T + 1e-9 * np.eye(w)
    rhs = rng.normal(size=(w,) if k == 0 else (w, k))
    G0, rhs0 = G.copy(), rhs.copy()
    try:
        ref = sla.cho_solve(sla.cho_factor(G, lower=True, check_finite=False), rhs, check_finite=False)
    except np.linalg.LinAlgError:
        with pytest.raises(np.linalg.LinAlgError):
            cho_solve(G, rhs)
        return
    out = cho_solve(G, rhs)
    assert out.shape == ref.shape and out.dtype == ref.dtype
    assert out.tobytes() == ref.tobytes()
    np.testing.assert_array_equal(G, G0)  # arguments untouched
    np.testing.assert_array_equal(rhs, rhs0)


def test_not_positive_definite_is_refused_as_scipy_does() -> None:
    G = np.array([[1.0, 2.0], [2.0, 1.0]])
    with pytest.raises(np.linalg.LinAlgError, match="not positive definite"):
        sla.cho_factor(G, lower=True, check_finite=False)
    with pytest.raises(np.linalg.LinAlgError, match="not positive definite"):
        cho_solve(G, np.ones(2))


def test_loads_without_scipy_linalg_in_a_fresh_interpreter() -> None:
    code = (
        "import json, sys\n"
        "import numpy as np\n"
        "from swarmdeck.safety.small_lapack import cho_solve\n"
        "x = cho_solve(np.array([[4.0, 1.0], [1.0, 3.0]]), np.array([1.0, 2.0]))\n"
        "alone = 'scipy.linalg' in sys.modules\n"
        "import scipy.linalg as sla\n"
        "y = sla.cho_solve(sla.cho_factor(np.array([[4.0, 1.0], [1.0, 3.0]]), lower=True), np.array([1.0, 2.0]))\n"
        "print(json.dumps({'alone': alone, 'same': x.tobytes() == y.tobytes(),\n"
        "                  'after': cho_solve(np.array([[4.0, 1.0], [1.0, 3.0]]), np.array([1.0, 2.0])).tobytes()\n"
        "                           == y.tobytes()}))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-4000:]
    assert json.loads(out.stdout.strip().splitlines()[-1]) == {"alone": False, "same": True, "after": True}
