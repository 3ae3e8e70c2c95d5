"""Minimal invasiveness: a nominal that satisfies every constraint comes back bit-for-bit."""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.safety import BarrierConfig, SafetyFilter
from swarmdeck.safety.scenes import grid_scene


@settings(max_examples=40, deadline=None)
@given(n=st.integers(1, 40), seed=st.integers(0, 2**31 - 1), scale=st.floats(0.0, 1.0))
def test_safe_nominal_returned_exactly(n: int, seed: int, scale: float) -> None:
    """Scale a filtered (hence safe) command: for b ≥ 0 the scaled rows stay satisfied."""
    rng = np.random.default_rng(seed)
    x, nominal = grid_scene(n, rng)
    f = SafetyFilter()
    u, diag = f.filter(x, nominal)
    assert diag.ok
    safe_nominal = u * scale
    before = safe_nominal.copy()
    out, d2 = f.filter(x, safe_nominal)
    assert d2.ok
    assert np.array_equal(safe_nominal, before)  # argument not mutated
    assert out is not safe_nominal
    np.testing.assert_allclose(out, safe_nominal, rtol=0, atol=1e-9)
    if d2.nominal_was_safe:
        assert np.array_equal(out, safe_nominal)
        assert d2.method == "pass-through" and np.all(d2.intervention == 0)


def test_far_apart_robots_pass_through_bitwise() -> None:
    rng = np.random.default_rng(5)
    x = np.array([[-1.0, -0.5], [1.0, 0.5], [0.0, 0.0], [-1.0, 0.5]])
    nominal = rng.uniform(-0.14, 0.14, (4, 2))
    out, diag = SafetyFilter().filter(x, nominal)
    assert diag.nominal_was_safe and diag.ok and diag.status == "nominal safe"
    assert np.array_equal(out, nominal)


def test_unsafe_nominal_is_changed() -> None:
    """The same check can fail: two robots driving head-on are modified."""
    x = np.array([[-0.1, 0.0], [0.1, 0.0]])
    nominal = np.array([[0.2, 0.0], [-0.2, 0.0]])
    out, diag = SafetyFilter().filter(x, nominal)
    assert diag.ok and not diag.nominal_was_safe
    assert np.all(diag.intervention > 0.1)
    assert out[0, 0] - out[1, 0] <= 1e-9 + BarrierConfig().gamma * (0.2**2 - 0.17**2) ** 3 / (2 * 0.2)
