"""Per-source calibration: surface (0..1, y down) → arena metres."""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.inputs import Calibration

CORNERS = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.5, 0.5]])


def test_default_maps_the_whole_surface_onto_the_arena_with_y_up():
    np.testing.assert_allclose(Calibration().to_arena(CORNERS),
                               [[-1.6, 1.0], [1.6, 1.0], [-1.6, -1.0], [1.6, -1.0], [0.0, 0.0]])


def test_other_bounds():
    cal = Calibration(bounds=(0.0, 4.0, 0.0, 2.0))
    np.testing.assert_allclose(cal.to_arena(CORNERS[[0, 3, 4]]), [[0.0, 2.0], [4.0, 0.0], [2.0, 1.0]])


def test_flips():
    np.testing.assert_allclose(Calibration(flip_x=True).to_arena(CORNERS[:1]), [[1.6, 1.0]])
    np.testing.assert_allclose(Calibration(flip_y=True).to_arena(CORNERS[:1]), [[-1.6, -1.0]])


def test_rotation_quarter_turn_ccw_in_surface_units():
    cal = Calibration(rotation=math.pi / 2)
    # top-right of the surface (u=1, v=0) is (+½, +½) centred; rotated CCW → (−½, +½)
    np.testing.assert_allclose(cal.to_arena(np.array([[1.0, 0.0]])), [[-1.6, 1.0]], atol=1e-12)
    np.testing.assert_allclose(cal.to_arena(np.array([[1.0, 0.5]])), [[0.0, 1.0]], atol=1e-12)


def test_scale_and_offset():
    cal = Calibration(scale=(0.5, 0.25), offset=(0.3, -0.2))
    np.testing.assert_allclose(cal.to_arena(CORNERS[[0, 4]]), [[-0.5, 0.05], [0.3, -0.2]])


@settings(max_examples=50, deadline=None)
@given(fx=st.booleans(), fy=st.booleans(), rot=st.floats(-math.pi, math.pi), sx=st.floats(0.1, 2.0),
       sy=st.floats(0.1, 2.0), ox=st.floats(-1, 1), oy=st.floats(-1, 1),
       uv=st.tuples(st.floats(0, 1), st.floats(0, 1)), duv=st.tuples(st.floats(-2, 2), st.floats(-2, 2)))
def test_velocity_is_the_derivative_of_the_position_map(fx, fy, rot, sx, sy, ox, oy, uv, duv):
    cal = Calibration(fx, fy, rot, (sx, sy), (ox, oy))
    p, d = np.array([uv]), np.array([duv])
    h = 1e-3
    fd = (cal.to_arena(p + h * d) - cal.to_arena(p - h * d)) / (2 * h)
    np.testing.assert_allclose(cal.velocity_to_arena(d), fd, atol=1e-9)
    assert cal.area_scale() == pytest.approx(sx * sy * 6.4)


def test_from_dict_and_its_errors():
    cal = Calibration.from_dict({"flip_x": True, "rotation_deg": 90, "scale": 0.5, "offset": [0.1, 0.2]})
    assert cal.flip_x and cal.rotation == pytest.approx(math.pi / 2) and cal.scale == (0.5, 0.5)
    with pytest.raises(ValueError, match="unknown calibration keys"):
        Calibration.from_dict({"flipx": True})
    with pytest.raises(ValueError, match="true/false"):
        Calibration.from_dict({"flip_x": "yes"})
    with pytest.raises(ValueError, match="min < max"):
        Calibration(bounds=(1.0, -1.0, 0.0, 1.0))
    with pytest.raises(ValueError, match="non-zero"):
        Calibration(scale=(0.0, 1.0))
