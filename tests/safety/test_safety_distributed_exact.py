"""The distributed filter's per-robot QP is solved exactly: agreement with clarabel on single-robot problems.

Each problem is one robot: min ‖u − û‖² s.t. a few random rows aᵀu ≤ b (random
directions and lengths, b of either sign) and either the speed disc ‖u‖ ≤ v_max
or, as in the unicycle form, no disc but a bounding polygon of rows. The
oracle is clarabel at tight tolerances on the same data: the enumeration's answer
must be feasible, no costlier than clarabel's (which sits up to ~1e-6 m/s off the
speed circle), within 1e-5 m/s of it, and "no answer" exactly when clarabel says
infeasible.
Several robots are solved in one call, so the vectorisation is exercised too.
"""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.safety.constraints import PAIR, Rows
from swarmdeck.safety.distributed import solve_small_qps
from swarmdeck.safety.qp_clarabel import solve_qp


def one_robot_rows(a: np.ndarray, b: np.ndarray) -> Rows:
    k = b.shape[0]
    i = np.zeros(k, dtype=np.int64)
    return Rows(i, np.full(k, -1), a, np.zeros_like(a), b, np.ones(k), np.full(k, PAIR, dtype=np.int8),
                np.arange(k, dtype=np.int64))


def random_problem(rng: np.random.Generator, disc: bool):
    k = int(rng.integers(0, 9))
    ang = rng.uniform(0, 2 * np.pi, k)
    a = np.stack([np.cos(ang), np.sin(ang)], axis=1) * rng.uniform(0.2, 3.0, (k, 1))
    b = rng.uniform(-0.15, 0.3, k) * np.linalg.norm(a, axis=1)
    if not disc:  # a bounding box, like the wheel-limit rows
        box = np.array([[1.0, 0.3], [-1.0, -0.3], [0.2, 1.0], [-0.2, -1.0]])
        a = np.concatenate([a, box])
        b = np.concatenate([b, np.full(4, 0.2)])
    uh = rng.normal(0, 0.2, 2)
    return a, b, uh


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), disc=st.booleans())
def test_each_robot_matches_clarabel(seed: int, disc: bool) -> None:
    rng = np.random.default_rng(seed)
    vmax = 0.2
    problems = [random_problem(rng, disc) for _ in range(12)]
    owner = np.concatenate([np.full(p[1].size, r) for r, p in enumerate(problems)]).astype(np.int64)
    a = np.concatenate([p[0] for p in problems]).reshape(-1, 2)
    b = np.concatenate([p[1] for p in problems])
    nominal = np.stack([p[2] for p in problems])
    reach = vmax if disc else 0.2 * np.sqrt(2) * 1.1 / 0.3  # a bound on ‖u‖ inside the box
    res = solve_small_qps(owner, a, b, nominal, vmax if disc else None, reach)
    for r, (ar, br, uh) in enumerate(problems):
        ref = solve_qp(one_robot_rows(ar, br), uh[None, :], vmax if disc else None, tol=1e-10, max_iter=200)
        if ref.ok:
            assert res.solved[r], f"robot {r}: clarabel solved it, the enumeration found no answer"
            assert np.abs(res.u[r] - ref.u[0]).max() < 1e-5, (res.u[r], ref.u[0])
            def cost(v, uh=uh):
                return float(np.sum((v - uh) ** 2))

            assert cost(res.u[r]) <= cost(ref.u[0]) + 1e-9  # clarabel is feasible only to ~1e-9
        elif ref.reason == "infeasible":
            assert not res.solved[r] and np.all(res.u[r] == 0)
        if res.solved[r]:
            assert np.all(ar @ res.u[r] <= br + 1e-9)
            if disc:
                assert np.linalg.norm(res.u[r]) <= vmax + 1e-12


def test_feasible_nominal_is_returned_bit_for_bit() -> None:
    owner = np.array([0, 1], dtype=np.int64)
    a = np.array([[1.0, 0.0], [0.0, 1.0]])
    b = np.array([0.1, 0.05])
    nominal = np.array([[0.1, 0.3], [0.013, 0.05]])  # robot 0 violates its disc, robot 1 is on its row
    res = solve_small_qps(owner, a, b, nominal, 0.2)
    assert np.array_equal(res.u[1], nominal[1])
    assert res.solved.all() and np.isclose(np.linalg.norm(res.u[0]), 0.2)


def test_closed_forms() -> None:
    # one violated row: the projection; two rows: their vertex; the disc: û scaled
    owner = np.array([0, 1, 1], dtype=np.int64)
    a = np.array([[1.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    b = np.array([0.05, 0.02, -0.01])
    nominal = np.array([[0.1, 0.1], [0.1, 0.1], [0.0, 0.0]])
    res = solve_small_qps(np.concatenate([owner]), a, b, nominal[:2], 0.2)
    np.testing.assert_allclose(res.u[0], [0.05, 0.1], atol=1e-15)
    np.testing.assert_allclose(res.u[1], [0.02, -0.01], atol=1e-15)
    assert res.active.all()
    res = solve_small_qps(np.zeros(0, dtype=np.int64), np.zeros((0, 2)), np.zeros(0), np.array([[0.3, 0.4]]), 0.2)
    np.testing.assert_allclose(res.u[0], [0.12, 0.16], atol=1e-15)
    assert res.on_disc[0]
