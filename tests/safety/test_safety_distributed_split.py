"""The half/half split (REFERENCE.md §12): the two robots' halves add up to the centralised pair row.

For every pair row k of a random scene the split gives exactly two rows, one
owned by each robot, with the pair row's coefficients and half its bound, so
for any commands the sum of the halves' left sides is the pair row's left side
and the sum of the bounds is its bound. Single-robot rows (walls, obstacles,
wheel limits) stay whole with their robot.
"""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core.kinematics import UnicycleParams
from swarmdeck.safety import BarrierConfig
from swarmdeck.safety.constraints import Rows, barrier_rows
from swarmdeck.safety.distributed import split_rows
from swarmdeck.safety.scenes import grid_scene
from swarmdeck.safety.unicycle import wheel_limit_rows


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 60))
def test_halves_add_up_to_the_pair_row(seed: int, n: int) -> None:
    rng = np.random.default_rng(seed)
    cfg = BarrierConfig()
    x, _ = grid_scene(n, rng, cfg)
    obstacles = rng.uniform(-1.2, 1.2, (3, 2))
    poses = np.concatenate([x, rng.uniform(-np.pi, np.pi, (n, 1))], axis=1)
    rows = Rows.concat([barrier_rows(x, cfg, obstacles), wheel_limit_rows(poses, UnicycleParams())])
    split = split_rows(rows)
    u = rng.normal(0, 0.2, (n, 2))
    own_lhs = np.einsum("kd,kd->k", split.a, u[split.owner])
    summed_lhs = np.bincount(split.source, own_lhs, minlength=rows.m)
    summed_b = np.bincount(split.source, split.b, minlength=rows.m)
    np.testing.assert_allclose(summed_lhs, rows.lhs(u), rtol=0, atol=1e-15)
    np.testing.assert_allclose(summed_b, rows.b, rtol=1e-15, atol=0)
    per_row = np.bincount(split.source, minlength=rows.m)
    pair = rows.j >= 0
    assert np.all(per_row[pair] == 2) and np.all(per_row[~pair] == 1)
    for k in np.flatnonzero(pair)[:20]:
        mine = split.source == k
        assert sorted(split.owner[mine].tolist()) == sorted([int(rows.i[k]), int(rows.j[k])])
        assert np.all(split.b[mine] == rows.b[k] / 2)
    single = ~pair[split.source]
    assert np.array_equal(split.owner[single], rows.i[split.source[single]])
    assert np.array_equal(split.b[single], rows.b[split.source[single]])
