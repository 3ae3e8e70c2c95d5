"""The coverage controller: one call per tick, state contents, bad input, run-time density swap."""
from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.coverage import (
    CoverageConfig,
    CoverageController,
    CoverageState,
    GaussianMixture,
    moving_density,
    s1_density,
)

BOUNDS = (-1.6, 1.6, -1.0, 1.0)


def test_one_tick_state(rng):
    p = rng.uniform([-1.5, -0.9], [1.5, 0.9], (30, 2))
    ctrl = CoverageController(CoverageConfig(), moving_density())
    u, st = ctrl(p, 1.5)
    assert isinstance(st, CoverageState) and st.ok and st.law == "tvd-d1"
    assert u.shape == (30, 2) and np.all(np.isfinite(u)) and np.hypot(*u.T).max() <= 0.2 + 1e-15
    assert st.centroids.shape == (30, 2) and st.masses.shape == (30,) and len(st.cells) == 30
    assert st.edges.shape == (st.neighbours.shape[0], 2, 2) and st.neighbours.shape[1] == 2
    d = np.hypot(*(st.centroids - p).T)
    assert st.mean_centroid_distance == pytest.approx(d.mean())
    assert st.max_centroid_distance == pytest.approx(d.max())
    assert st.cost_H_normalised == pytest.approx(st.cost_H / st.masses.sum())
    assert st.packing_warning is None and st.repaired == 0
    assert st.t == 1.5
    back = json.loads(json.dumps(st.to_dict(), allow_nan=False))
    np.testing.assert_array_equal(back["centroids"], st.centroids)
    assert len(back["cells"]) == 30 and back["status"] == "ok"
    with pytest.raises(ValueError):
        st.centroids[0, 0] = 1.0                   # state arrays are read-only


def test_density_can_be_swapped_at_run_time(rng):
    p = rng.uniform([-1.5, -0.9], [1.5, 0.9], (12, 2))
    ctrl = CoverageController(CoverageConfig(law="lloyd"), s1_density())
    _, a = ctrl(p, 0.0)
    ctrl.density = GaussianMixture(0.05, [[1.2, 0.7]], [0.2], [1.0])
    _, b = ctrl(p, 0.0)
    assert np.abs(a.centroids - b.centroids).max() > 1e-2
    with pytest.raises(TypeError):
        ctrl.density = "not a density"


def test_density_must_give_snapshots():
    class Bad:
        def at(self, t):
            return 3.0

    ctrl = CoverageController(CoverageConfig(), Bad())
    with pytest.raises(TypeError, match="GaussianMixture"):
        ctrl(np.zeros((3, 2)) + [[0, 0], [0.5, 0], [0, 0.5]], 0.0)
    with pytest.raises(ValueError):
        CoverageController(CoverageConfig(), None)


@pytest.mark.parametrize("bad", [np.full((3, 2), np.nan), np.zeros((3,)), np.zeros((2, 3)),
                                 np.zeros((0, 2))])
def test_malformed_positions_raise(bad):
    ctrl = CoverageController(CoverageConfig(), s1_density())
    with pytest.raises(ValueError, match="positions"):
        ctrl(bad, 0.0)


@pytest.mark.parametrize("points", [
    [[0.0, 0.0]],
    [[0.0, 0.0], [0.0, 0.0]],                                   # coincident
    [[-1.0, 0.0], [0.0, 0.0], [1.0, 0.0]],                      # collinear
    [[1.6, 0.0], [-1.6, -1.0], [5.0, 2.0], [0.0, 0.0]],          # on a wall, in a corner, outside
    [[0.3, 0.3]] * 6 + [[0.3, 0.3 + 1e-10]],                     # a pile-up
])
@pytest.mark.parametrize("law", ["lloyd", "lloyd-ff", "tvd-d1", "tvd-d2"])
def test_degenerate_positions_give_finite_commands(points, law):
    ctrl = CoverageController(CoverageConfig(law=law), moving_density())
    u, st = ctrl(np.array(points, dtype=float), 3.0)
    assert st.ok, st.status
    assert np.all(np.isfinite(u)) and np.all(np.isfinite(st.centroids))
    assert sum(c.shape[0] >= 3 for c in st.cells) == len(points)


def test_repairs_are_reported():
    ctrl = CoverageController(CoverageConfig(), s1_density())
    _, st = ctrl(np.array([[1.6, 0.0], [5.0, 2.0], [0.0, 0.0], [0.0, 0.0]]), 0.0)
    assert st.repaired == 4
    assert np.all(np.abs(st.positions[:, 0]) < 1.6) and np.all(np.abs(st.positions[:, 1]) < 1.0)


def test_no_floor_far_from_the_bump_still_gives_finite_commands():
    g = GaussianMixture(0.0, [[1.4, 0.8]], [0.03], [1.0])
    p = np.array([[-1.5, -0.9], [-1.0, -0.9], [-1.5, -0.5], [1.4, 0.7]])
    for law in ("lloyd", "tvd-d1"):
        u, st = CoverageController(CoverageConfig(law=law), g)(p, 0.0)
        assert st.ok and np.all(np.isfinite(u))


class _BrokenSnapshot(GaussianMixture):
    """A user-defined snapshot whose evaluation returns NaN (a bug in a user's density)."""

    __slots__ = ()

    def evaluate_both(self, q):
        phi, phi_t = super().evaluate_both(q)
        return phi * np.nan, phi_t

    def evaluate(self, q):
        return super().evaluate(q) * np.nan


def test_numerical_failure_stops_the_robots():
    g = _BrokenSnapshot(0.05, [[0.0, 0.0]], [0.3], [1.0])
    u, st = CoverageController(CoverageConfig(), g)(np.array([[0.0, 0.0], [0.5, 0.5]]), 0.0)
    assert not st.ok and "NaN" in st.status
    np.testing.assert_array_equal(u, 0.0)
    json.dumps(st.to_dict(), allow_nan=False)


def test_packing_warning_when_the_bump_is_too_narrow(rng):
    p = rng.uniform([-1.5, -0.9], [1.5, 0.9], (60, 2))
    narrow = GaussianMixture(0.005, [[0.0, 0.0]], [0.08], [1.0])
    ctrl = CoverageController(CoverageConfig(safety_distance=0.17), narrow)
    _, st = ctrl(p, 0.0)
    assert st.packing_warning is not None and "0.170" in st.packing_warning
    ctrl.density = GaussianMixture(0.2, [[0.0, 0.0]], [0.5], [1.0])
    _, st = ctrl(p, 0.1)
    assert st.packing_warning is None


_coord = st.one_of(st.floats(-2.0, 2.0), st.sampled_from([-1.6, 1.6, -1.0, 1.0, 0.0]))


@settings(max_examples=30, deadline=None)
@given(points=st.lists(st.tuples(_coord, _coord), min_size=1, max_size=25),
       dup=st.integers(0, 5), law=st.sampled_from(["lloyd", "lloyd-ff", "tvd-d1", "tvd-d2"]),
       t=st.floats(0.0, 30.0))
def test_any_positions_give_finite_saturated_commands(points, dup, law, t):
    p = np.array(points + points[:dup], dtype=float)        # walls, corners, outside, duplicates
    u, state = CoverageController(CoverageConfig(law=law), moving_density())(p, t)
    assert state.ok, state.status
    assert u.shape == p.shape and np.all(np.isfinite(u))
    assert np.hypot(*u.T).max() <= 0.2 + 1e-12
    assert len(state.cells) == len(p) and np.all(np.isfinite(state.centroids))
