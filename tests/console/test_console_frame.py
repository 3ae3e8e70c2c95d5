"""The Frame: immutable, and to_dict/from_dict round-trips exactly through strict JSON."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.console.runtime.frame import BarrierFrame, ContactsFrame, CoverageFrame, Frame
from swarmdeck.coverage import GaussianMixture


def make_frame(rng: np.random.Generator, n: int = 5, k: int = 2, with_parts: bool = True) -> Frame:
    e = 3 * n
    cells = [rng.normal(size=(int(rng.integers(3, 7)), 2)) for _ in range(n)]
    offsets = np.concatenate(([0], np.cumsum([len(c) for c in cells])))
    return Frame(
        tick=int(rng.integers(0, 10**6)), time=float(rng.uniform(0, 100)), run_time=float(rng.uniform(0, 50)),
        poses=rng.normal(size=(n, 3)), ids=np.arange(n), nominal=rng.normal(size=(n, 2)),
        safe=rng.normal(size=(n, 2)), v=rng.normal(size=n), w=rng.normal(size=n),
        seen=rng.uniform(size=n) > 0.3,
        barrier=BarrierFrame(ok=True, status="solved", solve_time_s=1e-3, n_constraints=7, n_active=k,
                             active_pairs=rng.integers(0, n, size=(k, 2)), active_h=rng.normal(size=k),
                             min_distance=0.2, min_wall_clearance=math.inf, intervention=rng.uniform(size=n))
        if with_parts else None,
        coverage=CoverageFrame(centroids=rng.normal(size=(n, 2)), masses=rng.uniform(size=n),
                               edges=rng.normal(size=(e, 2, 2)), neighbours=rng.integers(0, n, size=(e, 2)),
                               cost_H=0.123456789, mean_centroid_distance=0.02, packing_warning="tight",
                               cell_vertices=np.concatenate(cells), cell_offsets=offsets)
        if with_parts else None,
        density=GaussianMixture(0.05, mu=rng.normal(size=(k, 2)), sigma=rng.uniform(0.1, 0.4, k),
                                weight=rng.uniform(0, 1, k), mu_dot=rng.normal(size=(k, 2)))
        if with_parts else None,
        contacts=ContactsFrame(sources=("tuio", "browser"), ids=[3, 1], positions=rng.normal(size=(2, 2)),
                               velocities=np.zeros((2, 2))),
        behaviour="coverage", run_state="paused",
        params={"kappa": 1.0, "law": "tvd-d1", "gamma": 100.0, "barrier": True, "bad": math.nan},
        events=("a", "b"), alerts=("script failed",), health={"tuio:3333": "ok"},
        timing={"total": 0.004, "safety": 0.001},
    )


def roundtrip(f: Frame) -> Frame:
    return Frame.from_dict(json.loads(json.dumps(f.to_dict(), allow_nan=False)))


@settings(deadline=None, max_examples=25)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 12), k=st.integers(0, 4), parts=st.booleans())
def test_roundtrip_is_exact(seed: int, n: int, k: int, parts: bool) -> None:
    f = make_frame(np.random.default_rng(seed), n, k, parts)
    g = roundtrip(f)
    assert g.to_dict() == f.to_dict()
    np.testing.assert_array_equal(g.poses, f.poses)
    if parts:
        np.testing.assert_array_equal(g.coverage.edges, f.coverage.edges)
        assert [c.shape for c in g.coverage.cells()] == [c.shape for c in f.coverage.cells()]
        assert g.barrier.min_wall_clearance == math.inf
        assert math.isnan(g.params["bad"])
        np.testing.assert_array_equal(g.density.mu_dot, f.density.mu_dot)


def test_non_finite_array_entries_roundtrip() -> None:
    f = make_frame(np.random.default_rng(1), 3, 1)
    nominal = np.array(f.nominal)
    nominal[0, 1] = np.nan
    nominal[2, 0] = -np.inf
    g = Frame(**{**{k: getattr(f, k) for k in ("tick", "time", "poses", "ids", "safe", "v", "w")}, "nominal": nominal})
    h = roundtrip(g)
    assert math.isnan(h.nominal[0, 1]) and h.nominal[2, 0] == -np.inf
    assert h.nominal[1, 0] == g.nominal[1, 0]


def test_frame_is_immutable_and_copies_inputs() -> None:
    poses = np.zeros((2, 3))
    f = Frame(tick=0, time=0.0, poses=poses, ids=[0, 1], nominal=np.zeros((2, 2)), safe=np.zeros((2, 2)),
              v=np.zeros(2), w=np.zeros(2), params={"kappa": 1.0})
    poses[0, 0] = 5.0
    assert f.poses[0, 0] == 0.0
    with pytest.raises(ValueError):
        f.poses[0, 0] = 1.0
    with pytest.raises(AttributeError):
        f.tick = 3  # type: ignore[misc]
    with pytest.raises(TypeError):
        f.params["kappa"] = 2.0  # type: ignore[index]
    assert f.stopped


def test_bad_shapes_and_formats_are_named() -> None:
    with pytest.raises(ValueError, match="nominal"):
        Frame(tick=0, time=0.0, poses=np.zeros((2, 3)), ids=[0, 1], nominal=np.zeros((3, 2)),
              safe=np.zeros((2, 2)), v=np.zeros(2), w=np.zeros(2))
    with pytest.raises(ValueError, match="run_state"):
        Frame(tick=0, time=0.0, poses=np.zeros((1, 3)), ids=[0], nominal=np.zeros((1, 2)),
              safe=np.zeros((1, 2)), v=np.zeros(1), w=np.zeros(1), run_state="flying")
    d = make_frame(np.random.default_rng(2)).to_dict()
    with pytest.raises(ValueError, match="format"):
        Frame.from_dict({**d, "format": 99})
    d.pop("poses")
    with pytest.raises(ValueError, match="poses"):
        Frame.from_dict(d)
