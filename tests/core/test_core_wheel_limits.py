"""Wheel limits: one uniform scale per robot keeps the curvature and never exceeds 12.5 rad/s."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from swarmdeck.core.kinematics import GritsBotParams, limit_unicycle, unicycle_to_wheels, wheels_to_unicycle

P = GritsBotParams()
speeds = arrays(np.float64, 20, elements=st.floats(-5, 5, allow_nan=False))


@settings(max_examples=200, deadline=None)
@given(speeds, speeds)
def test_limits_respected_and_curvature_kept(v, w):
    lv, lw, sat = limit_unicycle(v, w, P)
    right, left = unicycle_to_wheels(lv, lw, P)
    assert np.all(np.abs(right) <= P.max_wheel_speed * (1 + 1e-12))
    assert np.all(np.abs(left) <= P.max_wheel_speed * (1 + 1e-12))
    # Same direction of motion: (lv, lw) is a non-negative multiple of (v, w).
    cross = lv * w - lw * v
    np.testing.assert_allclose(cross, 0.0, atol=1e-12)
    assert np.all(lv * v >= 0) and np.all(lw * w >= 0)
    # Unsaturated commands pass unchanged; saturated ones touch the limit.
    np.testing.assert_array_equal(lv[~sat], v[~sat])
    peak = np.maximum(np.abs(right), np.abs(left))
    np.testing.assert_allclose(peak[sat], P.max_wheel_speed)


def test_wheel_round_trip(rng):
    v = rng.uniform(-0.2, 0.2, 30)
    w = rng.uniform(-3, 3, 30)
    r, l = unicycle_to_wheels(v, w, P)
    v2, w2 = wheels_to_unicycle(r, l, P)
    np.testing.assert_allclose(v2, v, atol=1e-15)
    np.testing.assert_allclose(w2, w, atol=1e-14)


def test_max_speed_is_wheel_limit():
    r, l = unicycle_to_wheels(np.array([0.2]), np.array([0.0]), P)
    np.testing.assert_allclose(r, 12.5)
    np.testing.assert_allclose(l, 12.5)


def test_rps_clipping_would_change_direction_but_ours_does_not():
    v, w = np.array([0.2]), np.array([3.0])
    lv, lw, sat = limit_unicycle(v, w, P)
    assert sat[0]
    np.testing.assert_allclose(lw / lv, w / v)


@settings(max_examples=200, deadline=None)
@given(speeds, speeds)
def test_limiting_twice_changes_nothing(v, w):
    lv, lw, _ = limit_unicycle(v, w, P)
    lv2, lw2, sat2 = limit_unicycle(lv, lw, P)
    np.testing.assert_array_equal(lv2, lv)
    np.testing.assert_array_equal(lw2, lw)
    assert not sat2.any()
