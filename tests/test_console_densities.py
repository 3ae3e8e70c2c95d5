"""The console's densities: the circling bump, painted bumps (ramps, drags) and their merge.

The analytic φ_t each snapshot reports must match central finite differences of φ in time.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.console.runtime.density import BumpSet, MovingBump, merge_mixtures
from swarmdeck.coverage import GaussianMixture

Q = np.array([[0.0, 0.0], [0.5, -0.3], [-1.2, 0.7], [1.0, 0.5]])


def fd_phi_t(snapshot_at, t: float, h: float = 1e-5) -> np.ndarray:
    return (snapshot_at(t + h).evaluate(Q) - snapshot_at(t - h).evaluate(Q)) / (2 * h)


@settings(deadline=None, max_examples=20)
@given(t=st.floats(0.0, 40.0))
def test_moving_bump_phi_t_matches_finite_differences(t: float) -> None:
    m = MovingBump()
    np.testing.assert_allclose(m.at(t).evaluate_dt(Q), fd_phi_t(m.at, t), rtol=1e-5, atol=1e-8)
    np.testing.assert_allclose(np.linalg.norm(m.at(t).mu[0]), 0.6)


@settings(deadline=None, max_examples=20)
@given(t=st.floats(0.01, 0.39))
def test_ramp_in_and_out_phi_t_matches_finite_differences(t: float) -> None:
    bumps = BumpSet(ramp=0.4)
    bumps.add((0.5, -0.3), 0.3, 2.0, t=0.0)
    np.testing.assert_allclose(bumps.snapshot(t).evaluate_dt(Q), fd_phi_t(bumps.snapshot, t), rtol=1e-4, atol=1e-7)
    gone = BumpSet(ramp=0.4)
    bid = gone.add((0.5, -0.3), 0.3, 2.0, t=-5.0)
    gone.remove(bid, 0.0)
    np.testing.assert_allclose(gone.snapshot(t).evaluate_dt(Q), fd_phi_t(gone.snapshot, t), rtol=1e-4, atol=1e-7)


def test_ramp_weights_and_removal() -> None:
    bumps = BumpSet(ramp=0.4)
    bid = bumps.add((0.0, 0.0), 0.25, 1.5, t=1.0)
    assert bumps.snapshot(1.0).weight[0] == 0.0  # still a valid density thanks to the floor
    assert bumps.snapshot(1.2).weight[0] == pytest.approx(0.75)
    assert bumps.snapshot(2.0).weight[0] == pytest.approx(1.5)
    bumps.remove(bid, 3.0)
    assert bumps.snapshot(3.2).weight[0] == pytest.approx(0.75)
    assert bumps.snapshot(3.5) is None and bumps.live() == []


def test_dragged_bump_reports_its_velocity() -> None:
    bumps = BumpSet(extrapolate=0.1)
    bid = bumps.add((0.0, 0.0), 0.3, 1.0, t=0.0)
    bumps.move(bid, (0.10, 0.0), t=1.0)
    bumps.move(bid, (0.12, 0.01), t=1.1)  # 0.2 m/s along x, 0.1 m/s along y
    s = bumps.snapshot(1.15)
    np.testing.assert_allclose(s.mu_dot[0], (0.2, 0.1), atol=1e-12)
    np.testing.assert_allclose(s.mu[0], (0.13, 0.015), atol=1e-12)
    np.testing.assert_allclose(s.evaluate_dt(Q), fd_phi_t(bumps.snapshot, 1.15), rtol=1e-5, atol=1e-8)
    late = bumps.snapshot(2.0)  # extrapolation ended: still, and continuous
    np.testing.assert_allclose(late.mu_dot[0], (0.0, 0.0))
    np.testing.assert_allclose(late.mu[0], (0.14, 0.02), atol=1e-12)
    bumps.move(bid, (1.0, 1.0), t=5.0)  # a long pause: a jump, not a velocity
    np.testing.assert_allclose(bumps.snapshot(5.0).mu_dot[0], (0.0, 0.0))


def test_bad_bump_values_are_named() -> None:
    bumps = BumpSet(max_bumps=1)
    with pytest.raises(ValueError, match="sigma"):
        bumps.add((0, 0), 5.0, 1.0, 0.0)
    with pytest.raises(ValueError, match="weight"):
        bumps.add((0, 0), 0.3, -1.0, 0.0)
    with pytest.raises(ValueError, match="finite"):
        bumps.add((np.nan, 0), 0.3, 1.0, 0.0)
    bumps.add((0, 0), 0.3, 1.0, 0.0)
    with pytest.raises(ValueError, match="at most 1"):
        bumps.add((0, 0), 0.3, 1.0, 0.0)


def test_merge_keeps_every_bump_and_the_given_floor() -> None:
    a = GaussianMixture(0.3, mu=[[0.0, 0.0]], sigma=[0.2], weight=[1.0], mu_dot=[[0.1, 0.0]])
    b = GaussianMixture(0.7, mu=[[1.0, 0.0], [0.0, 1.0]], sigma=[0.3, 0.4], weight=[2.0, 0.5])
    m = merge_mixtures([a, None, b], floor=0.05)
    assert m.n_bumps == 3 and m.floor == 0.05
    np.testing.assert_allclose(m.evaluate(Q), a.evaluate(Q) + b.evaluate(Q) - 0.3 - 0.7 + 0.05)
    np.testing.assert_allclose(m.evaluate_dt(Q), a.evaluate_dt(Q) + b.evaluate_dt(Q))
    aniso = GaussianMixture(0.1, mu=[[0.5, 0.5]], weight=[1.0], cov=[[[0.04, 0.01], [0.01, 0.09]]])
    m2 = merge_mixtures([a, aniso], floor=0.05)
    np.testing.assert_allclose(m2.evaluate(Q), a.evaluate(Q) + aniso.evaluate(Q) - 0.3 - 0.1 + 0.05)
    assert merge_mixtures([None], floor=0.05).n_bumps == 0
