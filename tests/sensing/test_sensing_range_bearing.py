"""Range and bearing to neighbours (the GRITSBot's infrared abstraction, issue 28.1): closed-form ranges and
bearings in the observer's body frame, the radius and the field of view, noise and dropout statistics."""
from __future__ import annotations

import math

import numpy as np

from swarmdeck.sensing import RangeBearingConfig, range_and_bearing

EXACT = RangeBearingConfig(radius=1.0, range_sigma=0.0, bearing_sigma=0.0)


def test_ranges_and_bearings_are_in_the_observers_body_frame():
    poses = np.array([[0.0, 0.0, math.pi / 2], [0.0, 0.5, 0.0], [0.3, 0.0, math.pi], [2.0, 0.0, 0.0]])
    rb = range_and_bearing(poses, EXACT, np.random.default_rng(0))
    j, r, b = rb.of(0)
    assert j.tolist() == [1, 2]  # robot 3 is beyond the radius
    np.testing.assert_allclose(r, [0.5, 0.3])
    np.testing.assert_allclose(b, [0.0, -math.pi / 2], atol=1e-12)  # 1 straight ahead, 2 on its right
    j, r, b = rb.of(2)
    assert j.tolist() == [0, 1]
    np.testing.assert_allclose(b, [0.0, math.atan2(0.5, -0.3) - math.pi], atol=1e-12)  # 2 faces 0: dead ahead
    assert rb.of(3)[0].size == 0
    assert (np.diff(rb.i) >= 0).all()


def test_the_field_of_view_hides_what_is_behind():
    poses = np.array([[0.0, 0.0, 0.0], [0.4, 0.0, 0.0], [-0.4, 0.0, 0.0], [0.0, 0.4, 0.0]])
    cfg = RangeBearingConfig(radius=1.0, range_sigma=0.0, bearing_sigma=0.0, fov=math.pi)  # ±90°
    j, _, _ = range_and_bearing(poses, cfg, np.random.default_rng(0)).of(0)
    assert j.tolist() == [1, 3]


def test_noise_and_dropout_statistics():
    rng = np.random.default_rng(12)
    n = 400
    poses = np.column_stack((np.zeros(n), np.zeros(n), np.zeros(n)))
    poses[1::2, 0] = 0.2  # pairs of robots 0.2 m apart… all within 0.5 m of each other: a dense clique
    poses = poses[:60]
    cfg = RangeBearingConfig(radius=0.5, range_sigma=0.01, bearing_sigma=0.02, dropout=0.2)
    rb = range_and_bearing(poses, cfg, rng)
    total = 60 * 59
    kept = len(rb.i)
    assert abs(kept - 0.8 * total) <= 5 * math.sqrt(total * 0.2 * 0.8)
    far = rb.range > 0.1
    err = rb.range[far] - 0.2
    assert abs(err.mean()) < 5 * 0.01 / math.sqrt(far.sum()) and abs(err.std() / 0.01 - 1) < 0.1
