"""Closed-form checks of the exact unicycle step (core.kinematics.unicycle_step)."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.devices import unicycle_step


def test_straight_line():
    poses = np.array([[0.1, -0.2, np.pi / 3]])
    out = unicycle_step(poses, [0.2], [0.0], 0.5)
    np.testing.assert_allclose(out[0], [0.1 + 0.1 * np.cos(np.pi / 3), -0.2 + 0.1 * np.sin(np.pi / 3), np.pi / 3], atol=1e-15)


def test_pure_rotation_stays_in_place():
    out = unicycle_step(np.array([[0.3, 0.4, 0.0]]), [0.0], [2.0], 0.25)
    np.testing.assert_allclose(out[0], [0.3, 0.4, 0.5], atol=1e-15)


def test_full_circle_returns_home():
    poses = np.array([[-0.5, 0.25, 1.0]])
    v, w = 0.15, 1.2
    steps = 100
    dt = 2 * np.pi / w / steps
    p = poses
    for _ in range(steps):
        p = unicycle_step(p, [v], [w], dt)
    np.testing.assert_allclose(p[0, :2], poses[0, :2], atol=1e-12)
    assert abs(np.angle(np.exp(1j * (p[0, 2] - poses[0, 2])))) < 1e-12


def test_arc_matches_circle_geometry():
    # Centre of the turning circle: c = p + (v/w)(-sin θ, cos θ); the robot stays on it.
    p0 = np.array([[0.2, -0.1, 0.7]])
    v, w, dt = 0.2, -1.5, 0.4
    p1 = unicycle_step(p0, [v], [w], dt)[0]
    R = v / w
    centre = p0[0, :2] + R * np.array([-np.sin(0.7), np.cos(0.7)])
    assert abs(np.linalg.norm(p1[:2] - centre) - abs(R)) < 1e-14
    np.testing.assert_allclose(p1[2], 0.7 + w * dt)


@settings(max_examples=200, deadline=None)
@given(st.floats(-0.3, 0.3), st.floats(-1e-5, 1e-5), st.floats(-np.pi, np.pi))
def test_continuous_through_small_turn_rates(v, w, theta):
    """The series branch and the exact branch agree where they meet (ω·dt near 1e-6)."""
    dt = 0.033
    p = np.array([[0.0, 0.0, theta]])
    a = unicycle_step(p, [v], [w], dt)
    # Reference: many tiny Euler steps.
    q = p.copy()
    n = 2000
    for _ in range(n):
        q = q + np.array([[v * np.cos(q[0, 2]), v * np.sin(q[0, 2]), w]]) * (dt / n)
    np.testing.assert_allclose(a[0, :2], q[0, :2], atol=1e-9)


def test_vectorised_rows_independent(rng):
    poses = rng.uniform(-1, 1, (50, 3))
    v = rng.uniform(-0.2, 0.2, 50)
    w = rng.uniform(-5, 5, 50)
    together = unicycle_step(poses, v, w, 0.033)
    for i in range(0, 50, 7):
        np.testing.assert_allclose(unicycle_step(poses[i:i + 1], v[i:i + 1], w[i:i + 1], 0.033)[0], together[i])


def test_does_not_mutate_inputs(rng):
    poses = rng.uniform(-1, 1, (5, 3))
    keep = poses.copy()
    unicycle_step(poses, np.ones(5) * 0.1, np.ones(5), 0.033)
    np.testing.assert_array_equal(poses, keep)
