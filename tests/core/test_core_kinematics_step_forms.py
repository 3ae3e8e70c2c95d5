"""The simulator's unicycle step computes only the form its robots need (issue 28: the rps examples' step cost): when
every robot turns by more than the series' switch (or every one by less), the step gives the very bits of the
two-form expression (both forms computed, np.where picking), at and around the switch, with NaN and with ±0."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from swarmdeck.core.kinematics import unicycle_step, wrap_angle

SWITCH = 1e-6
DT = 0.033


def _both_forms(poses, v, w, dt):
    """unicycle_step as it was written: both forms for every robot, np.where picking."""
    theta = poses[:, 2]
    a = w * dt
    small = np.abs(a) < SWITCH
    a_safe = np.where(small, 1.0, a)
    f = np.where(small, 1.0 - a * a / 6.0, np.sin(a_safe) / a_safe)
    g = np.where(small, a / 2.0 - a**3 / 24.0, (1.0 - np.cos(a_safe)) / a_safe)
    d = v * dt
    c, s = np.cos(theta), np.sin(theta)
    out = np.empty_like(poses)
    out[:, 0] = poses[:, 0] + d * (f * c - g * s)
    out[:, 1] = poses[:, 1] + d * (f * s + g * c)
    out[:, 2] = wrap_angle(theta + a)
    return out


near = [0.0, -0.0, SWITCH / DT, -SWITCH / DT, np.nextafter(SWITCH / DT, 0), np.nextafter(SWITCH / DT, 1),
        1e-9, -3e-7, 5e-324, np.nan]
turn = st.one_of(st.floats(-10, 10), st.sampled_from(near))


@settings(max_examples=100, deadline=None)
@given(st.integers(1, 8).flatmap(lambda n: st.tuples(
    arrays(np.float64, (n, 3), elements=st.floats(-3, 3)), arrays(np.float64, n, elements=st.floats(-0.3, 0.3)),
    arrays(np.float64, n, elements=turn), st.sampled_from(["mixed", "all small", "none small"]))))
def test_one_form_is_the_bits_of_both(case):
    poses, v, w, which = case
    if which == "all small":
        w = np.where(np.isnan(w), 0.0, np.clip(w, -1e-5, 1e-5))
    elif which == "none small":
        w = np.where(np.abs(w * DT) < SWITCH, 1.0, w)
    with np.errstate(invalid="ignore"):
        want = _both_forms(poses, v, w, DT)
        got = unicycle_step(poses, v, w, DT)
    assert got.tobytes() == want.tobytes()
