"""The distributed filter's compiled per-robot QPs (issue 27 item 1) answer bit for bit as the numpy path.

``safety.distributed_kernel.solve_small_qps_kernel`` (numba, no GIL) replaces ``solve_small_qps``'s
vectorised numpy path above ``small_kernels.SMALL_ROBOTS`` robots. Both are run on the same problems —
random rows of random robots (walls, single rows of either sign, a bounding box instead of the disc),
the split rows of dense jammed scenes with and without the speed disc, subsets ``todo`` — and every
output (u, solved, active rows, on the disc) must be equal to the last bit.
"""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.safety import BarrierConfig, distributed
from swarmdeck.safety.constraints import barrier_rows
from swarmdeck.safety.distributed import _solve_small_qps_numpy, solve_small_qps, split_rows
from swarmdeck.safety.distributed_kernel import solve_small_qps_kernel
from swarmdeck.safety.scenes import arena_for, grid_scene


def both(owner: np.ndarray, a: np.ndarray, b: np.ndarray, nominal: np.ndarray, vmax: float | None,
         reach: float | None, todo: np.ndarray | None) -> None:
    ref = _solve_small_qps_numpy(owner, a, b, nominal, vmax, reach, todo)
    u, solved, active, on_disc, _ = solve_small_qps_kernel(
        owner.astype(np.int64), a, b, nominal, vmax is not None, np.inf if vmax is None else vmax,
        np.inf if reach is None else reach, np.zeros(0, bool) if todo is None else todo, todo is not None)
    assert np.array_equal(u, ref.u), np.abs(u - ref.u).max()
    assert np.array_equal(solved, ref.solved)
    assert np.array_equal(active, ref.active)
    assert np.array_equal(on_disc, ref.on_disc)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), disc=st.booleans(), with_todo=st.booleans())
def test_random_rows_bit_for_bit(seed: int, disc: bool, with_todo: bool) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 40))
    m = int(rng.integers(0, 8 * n))
    owner = rng.integers(0, n, m)
    ang = rng.uniform(0, 2 * np.pi, m)
    a = np.stack([np.cos(ang), np.sin(ang)], axis=1) * rng.uniform(0.2, 3.0, (m, 1))
    a[rng.random(m) < 0.05] = 0.0  # degenerate rows are skipped by both
    b = rng.uniform(-0.15, 0.3, m) * np.linalg.norm(a, axis=1)
    if not disc:  # a bounding box per robot, like the wheel-limit rows
        box = np.array([[1.0, 0.3], [-1.0, -0.3], [0.2, 1.0], [-0.2, -1.0]])
        owner = np.concatenate([owner, np.repeat(np.arange(n), 4)])
        a = np.concatenate([a, np.tile(box, (n, 1))])
        b = np.concatenate([b, np.full(4 * n, 0.2)])
    nominal = rng.normal(0, 0.2, (n, 2))
    todo = rng.random(n) < 0.7 if with_todo else None
    both(owner, a, b, nominal, 0.2 if disc else None, 0.3, todo)


@settings(max_examples=8, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(20, 300))
def test_jammed_scenes_bit_for_bit(seed: int, n: int) -> None:
    rng = np.random.default_rng(seed)
    cfg = BarrierConfig(bounds=arena_for(n, 0.188, fill=0.9))
    x, nominal = grid_scene(n, rng, cfg, pitch=0.188)
    split = split_rows(barrier_rows(x, cfg))
    both(split.owner, split.a, split.b, nominal, cfg.max_speed, cfg.max_speed, None)
    both(split.owner, split.a, split.b, -3.0 * nominal, None, cfg.max_speed, rng.random(n) < 0.5)


def test_the_public_function_takes_the_compiled_path_with_the_same_bits() -> None:
    rng = np.random.default_rng(3)
    cfg = BarrierConfig(bounds=arena_for(400, 0.188, fill=0.9))
    x, nominal = grid_scene(400, rng, cfg, pitch=0.188)
    split = split_rows(barrier_rows(x, cfg))
    got = solve_small_qps(split.owner, split.a, split.b, nominal, cfg.max_speed, cfg.max_speed)
    ref = _solve_small_qps_numpy(split.owner, split.a, split.b, nominal, cfg.max_speed, cfg.max_speed)
    assert np.array_equal(got.u, ref.u) and np.array_equal(got.active, ref.active)
    assert np.array_equal(got.solved, ref.solved) and np.array_equal(got.on_disc, ref.on_disc)


@settings(max_examples=6, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(20, 300))
def test_reallocation_and_certificate_bit_for_bit(seed: int, n: int) -> None:
    """The half/half split (``split_rows``), the second pass's (``reallocate_halves``), the consensus pass's
    (``consensus_shares``) and the certificate's worst row, compiled and numpy."""
    rng = np.random.default_rng(seed)
    cfg = BarrierConfig(bounds=arena_for(n, 0.188, fill=0.9))
    x, nominal = grid_scene(n, rng, cfg, pitch=0.188)
    rows = barrier_rows(x, cfg)
    split = split_rows(rows)
    u = solve_small_qps(split.owner, split.a, split.b, nominal, cfg.max_speed, cfg.max_speed).u
    n_pairs = int(np.sum(rows.j >= 0))
    b_c, loose_c = distributed.reallocate_halves(split, u, n_pairs)
    worst_c = distributed._worst_row(rows, u, rows.b)
    s_c, grown_c = distributed.consensus_shares(split, b_c, u, n_pairs)
    split_c = distributed.split_rows(rows)
    saved = distributed._COMPILED
    distributed._COMPILED = False
    try:
        b_n, loose_n = distributed.reallocate_halves(split, u, n_pairs)
        worst_n = distributed._worst_row(rows, u, rows.b)
        s_n, grown_n = distributed.consensus_shares(split, b_n, u, n_pairs)
        split_n = distributed.split_rows(rows)
    finally:
        distributed._COMPILED = saved
    assert np.array_equal(b_c, b_n) and np.array_equal(loose_c, loose_n)
    assert worst_c == worst_n
    assert np.array_equal(s_c, s_n) and np.array_equal(grown_c, grown_n)
    for field in ("owner", "a", "b", "source"):
        assert np.array_equal(getattr(split_c, field), getattr(split_n, field)), field
