"""Coverage laws: their definitions in terms of c, ∂c/∂t and J, saturation, the TVD-C guard."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from swarmdeck.coverage import CoverageConfig, coverage_tick, moving_density, parse_law, saturate
from swarmdeck.coverage.laws import law_command

BOUNDS = (-1.6, 1.6, -1.0, 1.0)


def _tick(law, p, t=2.0, kappa=1.3, **kw):
    cfg = CoverageConfig(law=law, kappa=kappa, max_speed=None, **kw)
    return coverage_tick(p, moving_density().at(t), cfg, t)


@pytest.fixture
def robots(rng):
    return rng.uniform([-1.5, -0.9], [1.5, 0.9], (25, 2))


def test_law_definitions(robots):
    _, st_l, _ = _tick("lloyd", robots)
    u_l, _, _ = _tick("lloyd", robots)
    u_ff, _, _ = _tick("lloyd-ff", robots)
    u_d1, _, jac = _tick("tvd-d1", robots)
    u_d3, _, _ = _tick("tvd-d3", robots)
    u_c, _, _ = _tick("tvd-c", robots, allow_centralised=True)
    c, cdot, p = st_l.centroids, st_l.dc_dt, st_l.positions
    b = 1.3 * (c - p) + cdot
    J = jac.toarray()
    np.testing.assert_allclose(u_l, 1.3 * (c - p), atol=1e-15)
    np.testing.assert_allclose(u_ff, b, atol=1e-15)
    np.testing.assert_allclose(u_d1.ravel(), b.ravel() + J @ b.ravel(), atol=1e-13)
    want3 = sum(np.linalg.matrix_power(J, k) @ b.ravel() for k in range(4))
    np.testing.assert_allclose(u_d3.ravel(), want3, atol=1e-12)
    np.testing.assert_allclose((np.eye(50) - J) @ u_c.ravel(), b.ravel(), atol=1e-10)


def test_tvd_d1_per_robot_uses_only_neighbours(robots):
    """u_i = b_i + Σ_{j ∈ N_i ∪ {i}} ∂c_i/∂p_j b_j (one hop)."""
    u, st, jac = _tick("tvd-d1", robots)
    b = 1.3 * (st.centroids - st.positions) + st.dc_dt
    J = jac.toarray().reshape(25, 2, 25, 2)
    for i in (0, 7, 19):
        nb = set(st.neighbours[st.neighbours[:, 0] == i, 1]) | set(st.neighbours[st.neighbours[:, 1] == i, 0])
        ui = b[i] + sum(J[i, :, j, :] @ b[j] for j in nb | {i})
        np.testing.assert_allclose(u[i], ui, atol=1e-13)


def test_lloyd_is_the_scaled_negative_gradient_of_H(robots):
    u, st, _ = _tick("lloyd", robots, kappa=0.7)
    grad = 2 * st.masses[:, None] * (st.positions - st.centroids)
    np.testing.assert_allclose(u, -0.7 / (2 * st.masses[:, None]) * grad, atol=1e-15)


@pytest.mark.parametrize("name, want", [("lloyd", ("lloyd", 0)), ("Lloyd+FF", ("lloyd-ff", 0)),
                                        ("tvd-d1", ("tvd-dk", 1)), ("TVD_D2", ("tvd-dk", 2)),
                                        ("tvd-dk", ("tvd-dk", 2)), ("tvd-c", ("tvd-c", 0))])
def test_parse_law(name, want):
    assert parse_law(name) == want


@pytest.mark.parametrize("bad", ["voronoi", "tvd-d0", "", "tvd-dx"])
def test_unknown_law_is_a_clear_error(bad):
    with pytest.raises(ValueError, match="law"):
        CoverageConfig(law=bad)


def test_tvd_c_needs_explicit_opt_in():
    with pytest.raises(ValueError, match="allow_centralised"):
        CoverageConfig(law="tvd-c")
    assert CoverageConfig(law="tvd-c", allow_centralised=True).law == "tvd-c"


def test_tvd_c_singular_system_is_a_clear_error():
    J = sp.csr_array(np.eye(4))           # I − J = 0
    with pytest.raises(RuntimeError, match="singular"):
        law_command("tvd-c", 0, 1.0, np.zeros((2, 2)), np.ones((2, 2)), np.zeros((2, 2)), J)


def test_saturation_keeps_direction_and_caps_speed(rng):
    u = rng.normal(0, 1, (50, 2))
    u[3] = [np.nan, 1.0]
    u[4] = [0.0, 0.0]
    s = saturate(u, 0.2)
    assert np.all(np.isfinite(s))
    np.testing.assert_array_equal(s[3], 0.0)
    speed = np.hypot(*s.T)
    assert speed.max() <= 0.2 + 1e-15
    fast = np.hypot(*u.T) > 0.2
    fast[3] = False
    np.testing.assert_allclose(speed[fast], 0.2)
    cos = (s[fast] * u[fast]).sum(1) / (np.hypot(*s[fast].T) * np.hypot(*u[fast].T))
    np.testing.assert_allclose(cos, 1.0)
    np.testing.assert_array_equal(saturate(u[:3], None), u[:3])


@pytest.mark.parametrize("law", ["lloyd", "lloyd-ff", "tvd-d1", "tvd-d2"])
def test_commands_are_saturated_and_finite(law, rng):
    p = rng.uniform([-1.6, -1.0], [1.6, 1.0], (60, 2))
    cfg = CoverageConfig(law=law, kappa=5.0, max_speed=0.1)
    u, st, _ = coverage_tick(p, moving_density().at(0.5), cfg, 0.5)
    assert np.all(np.isfinite(u)) and np.hypot(*u.T).max() <= 0.1 + 1e-15
    assert st.saturated > 0


@pytest.mark.parametrize("kwargs", [dict(kappa=0.0), dict(kappa=float("nan")), dict(max_speed=0.0),
                                    dict(bounds=(0, 0, 0, 1)), dict(safety_distance=-1.0),
                                    dict(packing_every=0), dict(hops=0, law="tvd-dk")])
def test_config_validation(kwargs):
    with pytest.raises(ValueError):
        CoverageConfig(**kwargs)


def test_config_from_a_toml_table():
    import tomllib

    cfg = CoverageConfig.from_dict(tomllib.loads(
        'law = "tvd-d2"\nkappa = 2.0\nbounds = [-2.0, 2.0, -1.0, 1.0]\n'
        '[quadrature]\nresolution = 0.8\n[edges]\nnodes = 8\n'))
    assert cfg.law == "tvd-d2" and cfg.kappa == 2.0 and cfg.bounds == (-2.0, 2.0, -1.0, 1.0)
    assert cfg.quadrature.resolution == 0.8 and cfg.edges.nodes == 8
    with pytest.raises(ValueError, match="unknown coverage config keys"):
        CoverageConfig.from_dict({"lawn": "lloyd"})
    with pytest.raises(ValueError, match="coverage.quadrature"):
        CoverageConfig.from_dict({"quadrature": {"fineness": 2}})
    with pytest.raises(ValueError, match="kappa"):
        CoverageConfig.from_dict({"kappa": -1.0})
