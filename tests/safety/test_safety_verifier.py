"""Simulation-based verifier: exact first-contact times, non-penetration, the safety score."""
from __future__ import annotations

import json

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.distance import pdist

from swarmdeck.safety import SafetyFilter
from swarmdeck.safety.verifier import first_contact_times, verify


def test_first_contact_closed_form() -> None:
    r0 = np.array([[1.0, 0.0], [1.0, 0.0], [0.2, 0.0], [1.0, 0.0], [0.0, 1.0]])
    vr = np.array([[-1.0, 0.0], [1.0, 0.0], [-1.0, 0.0], [-0.1, 0.0], [1.0, 0.0]])
    t = first_contact_times(r0, vr, 0.5, 1.0)
    assert t[0] == 0.5  # closes 1 → 0.5 at unit speed
    assert np.isinf(t[1])  # separating
    assert t[2] == 0.0  # already overlapping and approaching
    assert np.isinf(t[3])  # too slow to touch within dt
    assert np.isinf(t[4])  # passes by at distance 1


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-2, 2), min_size=4, max_size=4))
def test_first_contact_matches_sampling(v: list[float]) -> None:
    r0 = np.array([[v[0], v[1]]])
    vr = np.array([[v[2], v[3]]])
    d = 0.3
    t = first_contact_times(r0, vr, d, 1.0)[0]
    ts = np.linspace(0, 1, 20001)
    dist = np.linalg.norm(r0 + ts[:, None] * vr, axis=1)
    if np.linalg.norm(r0) <= d:
        return
    below = np.flatnonzero(dist < d - 1e-9)
    if np.isfinite(t):
        assert abs(np.linalg.norm(r0[0] + t * vr[0]) - d) < 1e-9
        assert below.size == 0 or ts[below[0]] >= t - 1e-4
    else:
        assert below.size == 0


def head_on(x: np.ndarray, t: float) -> np.ndarray:
    return np.array([[0.2, 0.0], [-0.2, 0.0]])


def test_head_on_without_filter_is_scored_and_stopped() -> None:
    x0 = np.array([[-0.5, 0.0], [0.5, 0.0]])
    rep = verify(x0, head_on, steps=200)
    assert rep.contacts and rep.score < 1
    first = rep.contacts[0]
    assert abs(first.time - (1.0 - 0.11) / 0.4) < 1e-9 and abs(first.approach_speed - 0.4) < 1e-12
    assert np.linalg.norm(rep.final_positions[0] - rep.final_positions[1]) >= 0.11 - 1e-9
    assert rep.contacts_per_robot.tolist() == [len(rep.contacts)] * 2
    json.dumps(rep.to_dict(), allow_nan=False)


def test_filtered_loop_scores_one() -> None:
    f = SafetyFilter()
    ell = 0.03

    def controller(x: np.ndarray, t: float) -> np.ndarray:
        u, diag = f.filter(x, 0.5 * (x.mean(axis=0) - x) + head_on_many(x))
        assert diag.ok
        return u

    def head_on_many(x: np.ndarray) -> np.ndarray:
        return np.where(x[:, :1] < 0, 0.1, -0.1) * np.array([[1.0, 0.0]])

    rng = np.random.default_rng(0)
    x0 = np.column_stack([np.linspace(-1.2, 1.2, 8), rng.uniform(-0.05, 0.05, 8)])
    rep = verify(x0, controller, steps=300, contact_distance=0.17 - 2 * ell)
    assert rep.score == 1.0 and not rep.contacts and rep.first_contact_time is None
    assert pdist(rep.final_positions).min() >= 0.17 - 1e-3
