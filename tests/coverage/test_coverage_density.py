"""Densities: closed-form values, analytic φ_t against finite differences in t, validation."""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.coverage import (
    AnalyticDensity,
    Bump,
    Constant,
    Density,
    Fixed,
    GaussianMixture,
    Linear,
    Lissajous,
    Orbit,
    Pulse,
    Sine,
    merge_mixtures,
    moving_density,
    s1_density,
)


def _fd_dt(density: Density, q: np.ndarray, t: float, h: float = 1e-5) -> np.ndarray:
    return (density.at(t + h).evaluate(q) - density.at(t - h).evaluate(q)) / (2 * h)


def test_evaluate_matches_closed_form(rng):
    g = GaussianMixture(0.05, mu=[[0.2, -0.1], [-0.7, 0.4]], sigma=[0.3, 0.15], weight=[1.0, 0.5])
    q = rng.uniform(-1.5, 1.5, (50, 2))
    want = 0.05 + np.exp(-((q - [0.2, -0.1]) ** 2).sum(1) / (2 * 0.09)) \
        + 0.5 * np.exp(-((q - [-0.7, 0.4]) ** 2).sum(1) / (2 * 0.0225))
    np.testing.assert_allclose(g.evaluate(q), want, rtol=1e-14)
    assert g.evaluate(q[0]).shape == ()
    assert g.evaluate(q.reshape(5, 10, 2)).shape == (5, 10)


def test_snapshot_is_its_own_density():
    g = GaussianMixture(0.1, mu=[[0, 0]], sigma=[0.2], weight=[1.0])
    assert isinstance(g, Density)
    assert g.at(0.0) is g and g.at(123.4) is g
    np.testing.assert_array_equal(g.evaluate_dt(np.zeros((3, 2))), 0.0)


def test_floor_only_density_is_uniform():
    g = GaussianMixture(0.3)
    assert g.n_bumps == 0 and g.sigma_min == math.inf
    np.testing.assert_array_equal(g.evaluate(np.ones((4, 2))), 0.3)


@pytest.mark.parametrize("density", [
    s1_density(),
    moving_density(),
    AnalyticDensity(0.03, (Bump(Orbit((0.2, 0.1), 0.5, 7.0), Sine(0.2, 0.05, 5.0), Constant(1.0),
                                aspect=2.5, angle=Sine(0.3, 1.0, 3.0)),
                           Bump(Fixed((-0.5, 0.0)), Constant(0.3), Constant(0.5)))),
    AnalyticDensity(0.02, (Bump(Linear((0.0, 0.0), (0.3, -0.2)), Sine(0.25, 0.1, 3.0), Pulse(1.0, 0.5, 2.5, 0.7)),
                           Bump(Lissajous((0.1, 0.2), (0.5, 0.3), (5.0, 7.0), (0.3, 1.0)),
                                Constant(0.2), Sine(0.8, 0.2, 4.0)))),
])
@pytest.mark.parametrize("t", [0.0, 0.9, 1.3, 2.8, 10.6])
def test_phi_t_matches_finite_difference_in_time(density, t, rng):
    q = rng.uniform([-1.6, -1.0], [1.6, 1.0], (200, 2))
    exact = density.at(t).evaluate_dt(q)
    fd = _fd_dt(density, q, t)
    assert np.abs(exact - fd).max() <= 1e-7 * max(1.0, np.abs(fd).max())


def test_fading_bump_has_finite_rate_from_zero_weight():
    d = AnalyticDensity(0.05, (Bump(Fixed((0.0, 0.0)), Constant(0.3), Pulse(1.0, 1.0, 3.0, 0.5)),))
    before, during, after = d.at(0.5), d.at(1.25), d.at(4.0)
    assert before.weight[0] == 0.0 and before.weight_dot[0] == 0.0
    assert 0.0 < during.weight[0] < 1.0 and during.weight_dot[0] > 0.0
    assert after.weight[0] == 0.0
    q = np.array([[0.0, 0.0], [0.2, 0.1]])
    np.testing.assert_allclose(during.evaluate_dt(q), _fd_dt(d, q, 1.25), rtol=1e-7)


@settings(max_examples=40, deadline=None)
@given(
    mu=st.lists(st.tuples(st.floats(-1.5, 1.5), st.floats(-0.9, 0.9)), min_size=1, max_size=4),
    data=st.data(),
)
def test_anisotropic_phi_t_matches_finite_difference(mu, data):
    k = len(mu)
    rot = np.array(data.draw(st.lists(st.floats(0, np.pi), min_size=k, max_size=k)))
    ax = np.array(data.draw(st.lists(st.tuples(st.floats(0.08, 0.5), st.floats(0.08, 0.5)),
                                     min_size=k, max_size=k)))
    c, s = np.cos(rot), np.sin(rot)
    R = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], 1)
    cov = R @ (ax[:, :, None] ** 2 * np.eye(2)) @ np.swapaxes(R, 1, 2)
    cov_dot = np.array([[[0.01, 0.004], [0.004, -0.006]]] * k)
    mu = np.array(mu)
    mu_dot = np.array([[0.2, -0.1]] * k)
    w = np.linspace(0.5, 1.0, k)
    wd = np.linspace(-0.2, 0.3, k)

    def snap(t):
        return GaussianMixture(0.05, mu + t * mu_dot, weight=w + t * wd, cov=cov + t * cov_dot)

    g = GaussianMixture(0.05, mu, weight=w, mu_dot=mu_dot, weight_dot=wd, cov=cov, cov_dot=cov_dot)
    q = np.random.default_rng(0).uniform([-1.6, -1.0], [1.6, 1.0], (60, 2))
    h = 1e-6
    fd = (snap(h).evaluate(q) - snap(-h).evaluate(q)) / (2 * h)
    assert np.abs(g.evaluate_dt(q) - fd).max() <= 1e-6 * max(1.0, np.abs(fd).max())
    np.testing.assert_allclose(g.evaluate(q), snap(0).evaluate(q), rtol=1e-12)
    assert g.sigma_min == pytest.approx(np.sqrt(np.linalg.eigvalsh(cov)[:, 0].min()), rel=1e-9)


def test_isotropic_and_equivalent_anisotropic_agree(rng):
    iso = GaussianMixture(0.05, [[0.1, 0.2]], [0.3], [1.0], [[0.1, 0.0]], [0.02], [0.1])
    ani = GaussianMixture(0.05, [[0.1, 0.2]], weight=[1.0], mu_dot=[[0.1, 0.0]], weight_dot=[0.1],
                          cov=[[[0.09, 0], [0, 0.09]]], cov_dot=[[[2 * 0.3 * 0.02, 0], [0, 2 * 0.3 * 0.02]]])
    q = rng.uniform(-1, 1, (30, 2))
    np.testing.assert_allclose(iso.evaluate(q), ani.evaluate(q), rtol=1e-14)
    np.testing.assert_allclose(iso.evaluate_dt(q), ani.evaluate_dt(q), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("kwargs, word", [
    (dict(mu=[[0, 0]], sigma=[0.2], weight=[-1.0]), "weight"),
    (dict(mu=[[0, 0]], sigma=[0.2], weight=[float("nan")]), "weight"),
    (dict(mu=[[0, 0]], sigma=[0.0], weight=[1.0]), "sigma"),
    (dict(mu=[[0, 0]], sigma=[-0.1], weight=[1.0]), "sigma"),
    (dict(mu=[[0, 0]], sigma=[float("nan")], weight=[1.0]), "sigma"),
    (dict(mu=[[0, float("nan")]], sigma=[0.2], weight=[1.0]), "mu"),
    (dict(mu=[[0, 0, 0]], sigma=[0.2], weight=[1.0]), "mu"),
    (dict(mu=[[0, 0]], sigma=[0.2, 0.3], weight=[1.0]), "sigma"),
    (dict(mu=[[0, 0]], sigma=[0.2], weight=[1.0], mu_dot=[[0, 0], [1, 1]]), "mu_dot"),
    (dict(mu=[[0, 0]], sigma=[0.2], weight=[1.0], sigma_dot=[float("inf")]), "sigma_dot"),
    (dict(mu=[[0, 0]], sigma=[0.2], weight=[1.0], weight_dot=["x"]), None),
    (dict(floor=-0.1), "floor"),
    (dict(floor=float("nan")), "floor"),
    (dict(floor=0.0), "zero mass"),
    (dict(mu=[[0, 0], [1, 1]], sigma=[0.2, 0.2], weight=[1e308, 1e308]), "overflows"),
    (dict(floor=0.0, mu=[[0, 0]], sigma=[0.2], weight=[0.0]), "zero mass"),
    (dict(mu=[[0, 0]], weight=[1.0], cov=[[[0.1, 0], [0, -0.1]]]), "cov"),
    (dict(mu=[[0, 0]], weight=[1.0], cov=[[[0.1, 0.2], [0.0, 0.1]]]), "cov"),
    (dict(mu=[[0, 0]], sigma=[0.2], weight=[1.0], cov=[[[0.1, 0], [0, 0.1]]]), "sigma"),
])
def test_bad_parameters_raise_clear_errors(kwargs, word):
    with pytest.raises(ValueError) as exc:
        GaussianMixture(**kwargs)
    if word is not None:
        assert word in str(exc.value)


def test_snapshot_is_immutable():
    g = GaussianMixture(0.05, [[0, 0]], [0.2], [1.0])
    with pytest.raises(AttributeError):
        g.floor = 1.0
    with pytest.raises(ValueError):
        g.mu[0, 0] = 3.0


def test_bad_query_shape():
    with pytest.raises(ValueError, match="q must have shape"):
        GaussianMixture(0.05, [[0, 0]], [0.2], [1.0]).evaluate(np.zeros((3, 3)))


def test_dict_round_trip(rng):
    for g in (moving_density().at(3.0),
              GaussianMixture(0.05, [[0, 0]], weight=[1.0], cov=[[[0.1, 0.02], [0.02, 0.05]]])):
        back = GaussianMixture.from_dict(g.to_dict())
        q = rng.uniform(-1, 1, (20, 2))
        np.testing.assert_array_equal(back.evaluate(q), g.evaluate(q))
        np.testing.assert_array_equal(back.evaluate_dt(q), g.evaluate_dt(q))
    with pytest.raises(ValueError, match="unknown"):
        GaussianMixture.from_dict({"floor": 0.1, "colour": 3})


def test_rotating_elongated_bump_has_the_right_shape():
    d = AnalyticDensity(0.0, (Bump(Fixed((0.0, 0.0)), Constant(0.1), Constant(1.0), aspect=3.0,
                                   angle=Constant(np.pi / 2)),))
    g = d.at(0.0)
    assert not g.isotropic
    np.testing.assert_allclose(g.std_min, [0.1]) and np.testing.assert_allclose(g.std_max, [0.3])
    # major axis along +y: one major std up is exp(-1/2), one minor std right too
    np.testing.assert_allclose(g.evaluate(np.array([[0.0, 0.3], [0.1, 0.0]])), np.exp(-0.5))
    with pytest.raises(ValueError, match="aspect"):
        Bump(Fixed((0, 0)), aspect=0.0)


def test_profiles_reject_bad_parameters():
    with pytest.raises(ValueError):
        Sine(0.3, 0.1, 0.0)
    with pytest.raises(ValueError):
        Pulse(ramp=0.0)
    with pytest.raises(ValueError):
        Orbit(period=0.0)
    bad = AnalyticDensity(0.05, (Bump(Fixed((0, 0)), Sine(0.1, 0.2, 4.0), Constant(1.0)),))
    with pytest.raises(ValueError, match="sigma"):
        bad.at(3.0)      # σ = 0.1 − 0.2 < 0
    negative = AnalyticDensity(0.05, (Bump(Fixed((0, 0)), Constant(0.2), Sine(0.5, 1.0, 4.0)),))
    negative.at(1.0)
    with pytest.raises(ValueError, match="bump 0: weight"):
        negative.at(3.0)  # w = 0.5 − 1.0 < 0


def test_merge_keeps_every_bump_and_the_given_floor() -> None:
    q = np.array([[0.0, 0.0], [0.5, -0.3], [-1.2, 0.7], [1.0, 0.5]])
    a = GaussianMixture(0.3, mu=[[0.0, 0.0]], sigma=[0.2], weight=[1.0], mu_dot=[[0.1, 0.0]])
    b = GaussianMixture(0.7, mu=[[1.0, 0.0], [0.0, 1.0]], sigma=[0.3, 0.4], weight=[2.0, 0.5])
    m = merge_mixtures([a, None, b], floor=0.05)
    assert m.n_bumps == 3 and m.floor == 0.05
    np.testing.assert_allclose(m.evaluate(q), a.evaluate(q) + b.evaluate(q) - 0.3 - 0.7 + 0.05)
    np.testing.assert_allclose(m.evaluate_dt(q), a.evaluate_dt(q) + b.evaluate_dt(q))
    aniso = GaussianMixture(0.1, mu=[[0.5, 0.5]], weight=[1.0], cov=[[[0.04, 0.01], [0.01, 0.09]]])
    m2 = merge_mixtures([a, aniso], floor=0.05)
    np.testing.assert_allclose(m2.evaluate(q), a.evaluate(q) + aniso.evaluate(q) - 0.3 - 0.1 + 0.05)
    assert merge_mixtures([None], floor=0.05).n_bumps == 0
