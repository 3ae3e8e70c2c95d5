"""Assignment: N charged, healthy robots to experiment ids; never a low or unknown battery."""
import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.devices.fleet import AssignmentError, AssignmentPolicy, assign

POLICY = AssignmentPolicy(min_charge=0.5)


@settings(max_examples=40)
@given(charge=st.lists(st.one_of(st.floats(0.0, 1.0), st.just(float("nan"))), min_size=1, max_size=30),
       n=st.integers(1, 30), seed=st.integers(0, 2**16))
def test_assignment_never_picks_a_low_or_unknown_battery(charge, n, seed):
    q = np.array(charge)
    m = len(q)
    rng = np.random.default_rng(seed)
    ids = rng.permutation(100)[:m]
    pos = rng.uniform(-1, 1, (m, 2))
    goals = rng.uniform(-1, 1, (n, 3))
    eligible = ~np.isnan(q) & (q >= 0.5)
    if eligible.sum() < n:
        with pytest.raises(AssignmentError, match=f"needs {n} robots but only {eligible.sum()} of the fleet's {m}"):
            assign(n, ids, q, 0.0, 0.0, positions=pos, goals=goals, policy=POLICY)
        return
    for kwargs in ({}, dict(positions=pos, goals=goals)):
        a = assign(n, ids, q, 0.0, 0.0, policy=POLICY, **kwargs)
        assert len(set(a.rows.tolist())) == n and np.all(eligible[a.rows])
        assert np.array_equal(a.ids, ids[a.rows])
        assert sorted(a.rows.tolist() + a.idle.tolist()) == list(range(m))


def test_the_error_names_every_robot_left_out_and_why():
    q = np.array([0.9, np.nan, 0.2, 0.8, 0.95])
    pose_age = np.array([0.1, 0.1, 0.1, 5.0, 0.1])
    status_age = np.array([0.5, 0.5, 0.5, 0.5, np.inf])
    with pytest.raises(AssignmentError) as err:
        assign(2, [10, 11, 12, 13, 14], q, pose_age, status_age, policy=POLICY)
    msg = str(err.value)
    assert "needs 2 robots but only 1" in msg
    assert "robot 11: battery reads NaN" in msg and "robot 12: battery 20% < 50%" in msg
    assert "robot 13: not tracked for 5.0 s" in msg and "robot 14: firmware silent for inf s" in msg
    assert "robot 10" not in msg


def test_without_goals_the_best_charged_are_taken():
    a = assign(2, [5, 6, 7, 8], [0.6, 0.9, 0.9, 0.7], 0.0, 0.0, policy=POLICY)
    assert a.ids.tolist() == [6, 7] and a.idle.tolist() == [0, 3]


def test_with_goals_the_total_distance_is_the_least_possible():
    rng = np.random.default_rng(3)
    pos = rng.uniform(-1.5, 1.5, (6, 2))
    goals = rng.uniform(-1.0, 1.0, (4, 3))
    a = assign(4, np.arange(6), np.ones(6), 0.0, 0.0, positions=pos, goals=goals, policy=POLICY)
    def cost(rows):
        return np.hypot(*(pos[list(rows)] - goals[:, :2]).T).sum()

    best = min(itertools.permutations(range(6), 4), key=cost)
    assert np.isclose(cost(a.rows), cost(best))


def test_bad_requests_are_named():
    with pytest.raises(ValueError, match="at least one robot"):
        assign(0, [1], [1.0], 0.0, 0.0)
    with pytest.raises(ValueError, match="goals need the robots' positions"):
        assign(1, [1], [1.0], 0.0, 0.0, goals=np.zeros((1, 3)))
    with pytest.raises(ValueError, match="min_charge"):
        AssignmentPolicy(min_charge=1.5)
