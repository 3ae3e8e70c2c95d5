"""The console's densities: the circling bump (S1 with parameters), painted bumps (ramps, drags).

The analytic φ_t each snapshot reports must match central finite differences of φ in time, and a
painted bump fades exactly as a touch contact does (one fade, owned by swarmdeck.inputs).
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.console.runtime.density import BumpSet
from swarmdeck.console.runtime.loop import DensityParams
from swarmdeck.coverage import s1_density
from swarmdeck.inputs import Contact, ContactDensity, DensityConfig

Q = np.array([[0.0, 0.0], [0.5, -0.3], [-1.2, 0.7], [1.0, 0.5]])


def fd_phi_t(snapshot_at, t: float, h: float = 1e-5) -> np.ndarray:
    return (snapshot_at(t + h).evaluate(Q) - snapshot_at(t - h).evaluate(Q)) / (2 * h)


@settings(deadline=None, max_examples=20)
@given(t=st.floats(0.0, 40.0))
def test_moving_bump_phi_t_matches_finite_differences(t: float) -> None:
    p = DensityParams()
    m = s1_density(p.radius, p.period, p.sigma, p.weight, p.floor)
    np.testing.assert_allclose(m.at(t).evaluate_dt(Q), fd_phi_t(m.at, t), rtol=1e-5, atol=1e-8)
    np.testing.assert_allclose(np.linalg.norm(m.at(t).mu[0]), 0.6)
    wide = s1_density(radius=0.3, period=5.0, sigma=0.2, weight=2.0, floor=0.1).at(t)
    np.testing.assert_allclose(wide.evaluate(wide.mu), 2.1)
    np.testing.assert_allclose(np.linalg.norm(wide.mu_dot[0]), 0.3 * 2 * np.pi / 5.0)


def test_bad_circling_bump_values_are_named() -> None:
    with pytest.raises(ValueError, match="moving density sigma must be > 0"):
        DensityParams(sigma=0.0)
    with pytest.raises(ValueError, match="moving density radius must be >= 0"):
        DensityParams(radius=-0.1)


@settings(deadline=None, max_examples=30)
@given(t=st.floats(0.0, 3.0), up=st.floats(0.6, 2.0))
def test_a_painted_bump_fades_like_a_touch(t: float, up: float) -> None:
    """Put down at 0 s, lifted/removed at ``up`` s (after the fade-in): the same weight and rate."""
    cfg = DensityConfig(weight=1.5, sigma=0.3, fade=0.4)
    touch = ContactDensity(cfg)
    touch.update([Contact("tuio", 1, np.array([0.2, 0.1]), np.zeros(2))], 0.0)
    if t >= up:  # a contact density is told about the lift when it happens (it is read forward in time)
        touch.update([], up)
    bumps = BumpSet(ramp=cfg.fade)
    bid = bumps.add((0.2, 0.1), cfg.sigma, cfg.weight, t=0.0)
    bumps.remove(bid, up)
    painted, touched = bumps.snapshot(t), touch.at(t)
    if t - up >= cfg.fade:
        assert painted is None
        return
    np.testing.assert_allclose(painted.weight, touched.weight, atol=1e-12)
    np.testing.assert_allclose(painted.weight_dot, touched.weight_dot, atol=1e-12)


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
