"""One speed limit for single-integrator commands: direction kept, NaN and inf rows stop the robot.

The defect this pins: devices' ``saturate_norm`` let a NaN row through (NaN > limit is False, so
its scale was 1) while coverage's ``saturate`` zeroed it; an inf row became NaN (inf · 0).
"""
import numpy as np
from hypothesis import example, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from swarmdeck.core.kinematics import saturate


@settings(max_examples=100, deadline=None)
@given(arrays(np.float64, (12, 2), elements=st.floats(-10, 10)), st.floats(0.0, 2.0))
@example(np.array([[1.11253693e-308, 0.0]] + [[0.0, 0.0]] * 11), 1e-307)  # a subnormal speed under the limit
@example(np.full((12, 2), 4.0), 2.2250738585e-313)  # a subnormal limit: the scaled rows came out 1 ulp too long
def test_norm_bounded_direction_kept(u, limit):
    s = saturate(u, limit)
    speed = np.hypot(u[:, 0], u[:, 1])
    assert np.all(np.hypot(s[:, 0], s[:, 1]) <= limit * (1 + 1e-12))
    assert np.all(np.abs(u[:, 0] * s[:, 1] - u[:, 1] * s[:, 0]) <= 1e-12 * (1 + speed))  # parallel
    assert np.all(u[:, 0] * s[:, 0] + u[:, 1] * s[:, 1] >= 0)  # same sense
    slow = speed <= limit
    np.testing.assert_array_equal(s[slow], u[slow])  # commands within the limit pass bit for bit


def test_non_finite_rows_become_zero_and_argument_is_untouched():
    u = np.array([[np.nan, 0.1], [np.inf, 0.0], [0.3, 0.4], [0.01, -0.02]])
    before = u.copy()
    s = saturate(u, 0.2)
    np.testing.assert_array_equal(s[[0, 1, 3]], [[0.0, 0.0], [0.0, 0.0], [0.01, -0.02]])
    np.testing.assert_allclose(s[2], [0.12, 0.16], rtol=1e-15)
    np.testing.assert_array_equal(u, before)
    np.testing.assert_array_equal(saturate(u, None)[:2], np.zeros((2, 2)))
    np.testing.assert_array_equal(saturate(u, np.inf)[2:], u[2:])
