"""One robot-constants hierarchy: a GritsBotParams is the UnicycleParams the barrier filter takes."""
import dataclasses

import numpy as np
import pytest

from swarmdeck.core.bounds import DEFAULT_BOUNDS, check_bounds
from swarmdeck.core.kinematics import GritsBotParams, UnicycleParams, limit_unicycle, si_to_unicycle
from swarmdeck.core.smooth import inverse_smoothstep, smoothstep
from swarmdeck.safety import UnicycleSafetyFilter


def test_gritsbot_is_a_unicycle_with_a_body():
    g = GritsBotParams(lookahead=0.05)
    assert isinstance(g, UnicycleParams)
    assert {f.name for f in dataclasses.fields(UnicycleParams)} < {f.name for f in dataclasses.fields(g)}
    assert g.max_linear_speed == pytest.approx(g.max_speed) and g.radius == pytest.approx(0.055)
    assert UnicycleSafetyFilter(params=g).params is g  # no field-by-field conversion


def test_filter_gives_the_same_commands_for_either_params(rng):
    poses = np.column_stack([rng.uniform(-0.3, 0.3, (6, 2)), rng.uniform(-np.pi, np.pi, 6)])
    v, w, _ = limit_unicycle(*si_to_unicycle(poses, rng.uniform(-0.2, 0.2, (6, 2)), 0.03), GritsBotParams())
    a = UnicycleSafetyFilter(params=UnicycleParams()).filter(poses, v, w)
    b = UnicycleSafetyFilter(params=GritsBotParams()).filter(poses, v, w)
    np.testing.assert_array_equal(a[0], b[0])
    np.testing.assert_array_equal(a[1], b[1])


@pytest.mark.parametrize("cls, field", [(UnicycleParams, "lookahead"), (GritsBotParams, "diameter"),
                                        (GritsBotParams, "wheel_radius")])
def test_bad_constants_named(cls, field):
    with pytest.raises(ValueError, match=rf"{cls.__name__}\.{field}"):
        cls(**{field: float("nan")})


@pytest.mark.parametrize("bad", [(0, 1, 0), (1, 0, 0, 1), (0, np.inf, 0, 1), "wide", (0, 1, 0, float("nan"))])
def test_bounds_checked(bad):
    with pytest.raises(ValueError, match="arena bounds must be .*min < max"):
        check_bounds(bad, "arena bounds")
    assert check_bounds([-1.6, 1.6, -1, 1]) == DEFAULT_BOUNDS


def test_smoothstep_closed_form():
    u = np.array([-1.0, 0.0, 0.25, 0.5, 1.0, 2.0])
    s, ds = smoothstep(u)
    np.testing.assert_allclose(s, [0, 0, 0.15625, 0.5, 1, 1])
    np.testing.assert_allclose(ds, [0, 0, 1.125, 1.5, 0, 0])
    for f in (0.0, 0.1, 0.5, 0.9, 1.0):
        assert smoothstep(inverse_smoothstep(f))[0] == pytest.approx(f, abs=1e-12)
