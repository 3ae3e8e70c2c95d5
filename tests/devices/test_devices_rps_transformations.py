"""rps.utilities.transformations facade: rps's closed forms, inputs never modified."""
import numpy as np
from hypothesis import example, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from swarmdeck.devices.rps.utilities.transformations import (
    create_si_to_uni_dynamics,
    create_si_to_uni_dynamics_with_backwards_motion,
    create_si_to_uni_mapping,
    create_uni_to_si_dynamics,
)

finite = st.floats(-1.0, 1.0, allow_nan=False)


@settings(max_examples=50, deadline=None)
@given(dxi=arrays(float, (2, 4), elements=finite), th=arrays(float, (4,), elements=st.floats(-3.2, 3.2)))
@example(dxi=np.array([[-5e-324, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]]), th=np.zeros(4))  # 0.5·v underflows to −0.0
def test_heading_maps_match_rps(dxi, th):
    poses = np.vstack((np.zeros((2, 4)), th))
    keep = dxi.copy(), poses.copy()
    v = np.cos(th) * dxi[0] + np.sin(th) * dxi[1]
    perp = -np.sin(th) * dxi[0] + np.cos(th) * dxi[1]
    fwd = create_si_to_uni_dynamics(0.5, 2.0)(dxi, poses)
    # a zero command turns nowhere (rps: atan2(0, -0.0) = π): signed zeros dropped after the gain
    fv, v, perp = 0.5 * v + 0.0, v + 0.0, perp + 0.0
    assert np.allclose(fwd, [fv, 2.0 * np.arctan2(perp, fv) / (np.pi / 2)])
    back = create_si_to_uni_dynamics_with_backwards_motion()(dxi, poses)  # rps: the same heading map
    assert np.allclose(back, [v, np.pi * np.arctan2(perp, v) / (np.pi / 2)])
    assert np.array_equal(dxi, keep[0]) and np.array_equal(poses, keep[1])


def test_mapping_round_trip():
    rng = np.random.default_rng(0)
    poses = rng.uniform(-1, 1, (3, 6))
    u = rng.uniform(-0.1, 0.1, (2, 6))
    to_uni, to_si_states = create_si_to_uni_mapping(angular_velocity_limit=np.inf)
    assert np.allclose(create_uni_to_si_dynamics()(to_uni(u, poses), poses), u)
    assert to_si_states(poses).shape == (2, 6)
