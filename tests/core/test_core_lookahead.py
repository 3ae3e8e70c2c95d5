"""The look-ahead diffeomorphism: round trips and agreement with the true point velocity."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core.kinematics import lookahead_points, si_to_unicycle, unicycle_step, unicycle_to_si


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 2**31 - 1), st.floats(0.01, 0.1))
def test_round_trip(seed, ell):
    rng = np.random.default_rng(seed)
    poses = rng.uniform(-np.pi, np.pi, (10, 3))
    u = rng.uniform(-0.3, 0.3, (10, 2))
    v, w = si_to_unicycle(poses, u, ell)
    np.testing.assert_allclose(unicycle_to_si(poses, v, w, ell), u, atol=1e-12)


def test_point_velocity_matches_finite_difference(rng):
    ell = 0.03
    poses = rng.uniform(-1, 1, (8, 3))
    v = rng.uniform(-0.2, 0.2, 8)
    w = rng.uniform(-2, 2, 8)
    h = 1e-6
    fd = (lookahead_points(unicycle_step(poses, v, w, h), ell) - lookahead_points(unicycle_step(poses, v, w, -h), ell)) / (2 * h)
    np.testing.assert_allclose(unicycle_to_si(poses, v, w, ell), fd, rtol=1e-6, atol=1e-9)


def test_points_are_ahead_of_centres():
    p = lookahead_points(np.array([[1.0, 2.0, np.pi / 2]]), 0.05)
    np.testing.assert_allclose(p, [[1.0, 2.05]], atol=1e-15)
