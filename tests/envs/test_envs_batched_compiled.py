"""BatchedSwarm.tick's compiled kernels (envs/batched_kernels.py) give the numpy pipeline's bits: the arena's
certify, wheel limits and exact unicycle step, including the rows the closed-loop equality test rarely reaches —
NaN/inf commands (that robot stops), saturated wheels (one scale per robot), turns below the series switch
(|ω·dt| < 1e-6, the Taylor branch) and headings across ±π — with the barrier off and on."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.core.compiled import AVAILABLE
from swarmdeck.envs.batched_kernels import COMPILED_FROM
from swarmdeck.envs.batched_swarm import BatchedSwarm


def _scene(rng: np.random.Generator, e: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    xy = rng.uniform([-1.4, -0.9], [1.4, 0.9], (e, n, 2))
    theta = rng.uniform(-np.pi, np.pi, (e, n, 1))
    theta[0, :3, 0] = (np.pi, -np.pi + 1e-15, np.pi - 1e-16)  # headings at the wrap
    poses = np.concatenate((xy, theta), axis=2)
    u = rng.normal(0.0, 0.15, (e, n, 2))
    u[0, 0] = (np.nan, 0.1)  # invalid rows: the robot stops
    u[1, 1] = (np.inf, -np.inf)
    u[0, 2] = (3.0, -2.0)  # far beyond the wheels: scaled down
    # a look-ahead velocity along the heading turns by exactly 0 (a = 0), a tiny sideways one below the switch
    th = poses[1, 2:6, 2]
    u[1, 2:4] = 0.1 * np.stack((np.cos(th[:2]), np.sin(th[:2])), axis=1)
    u[1, 4:6] = 0.1 * np.stack((np.cos(th[2:]), np.sin(th[2:])), axis=1) + 1e-10 * np.stack(
        (-np.sin(th[2:]), np.cos(th[2:])), axis=1)
    return poses, u


@pytest.mark.skipif(not AVAILABLE, reason="numba is a dependency; without it tick is the numpy path itself")
@pytest.mark.parametrize("safety", [False, True])
def test_compiled_tick_equals_the_numpy_pipeline_bit_for_bit(safety: bool) -> None:
    rng = np.random.default_rng(7)
    e, n = 6, 12  # E·N >= COMPILED_FROM: the compiled path even before numba is imported
    assert e * n >= COMPILED_FROM
    fast = BatchedSwarm(e, n, safety=safety)
    slow = BatchedSwarm(e, n, safety=safety)
    poses, u = _scene(rng, e, n)
    fast.set_poses(poses)
    slow.set_poses(poses)
    small_turns = 0
    for t in range(6):
        before = fast.poses[1, 2:6, 2].copy()
        a = fast.tick(u, check=True)
        b = slow._tick_numpy(u.reshape(-1, 2), check=True)
        assert np.array_equal(fast.poses, slow.poses), t
        assert np.array_equal(fast.points(), slow.points()), t
        for field in ("filter_change", "command_change", "filter_ok", "collision", "boundary"):
            assert np.array_equal(getattr(a, field), getattr(b, field)), (t, field)
        small_turns += int(np.count_nonzero(np.abs(fast.poses[1, 2:6, 2] - before) < 1e-6))
        u = u + rng.normal(0.0, 0.01, u.shape)
    assert np.all(fast.poses[0, 0] == poses[0, 0])  # the NaN row stopped (its robot never moved)
    assert small_turns > 0


def test_poses_are_read_only_and_points_are_fresh_arrays() -> None:
    sim = BatchedSwarm(2, 3, safety=False)
    with pytest.raises(ValueError):
        sim.poses[0, 0, 0] = 1.0  # the cached cos/sin θ would go stale: place robots with set_poses
    p = sim.points()
    p[:] = 5.0  # the caller's copy
    assert not np.array_equal(sim.points(), p)


def _pair_keys(pairs: np.ndarray, m: int) -> np.ndarray:
    return np.sort(pairs[:, 0].astype(np.int64) * m + pairs[:, 1])


@pytest.mark.skipif(not AVAILABLE, reason="numba is a dependency; without it the queries are the k-d tree itself")
def test_compiled_neighbour_queries_equal_the_lifted_k_d_tree() -> None:
    from swarmdeck.envs.neighbours import batched_query, lifted_tree, swarm_pairs

    rng = np.random.default_rng(12)
    for e, n, k, spread in ((64, 10, 3, 1.5), (3, 60, 5, 2.0), (2, 400, 4, 6.0), (4, 2, 1, 1.0)):
        pts = rng.uniform(-spread, spread, (e, n, 2))
        if n == 60:
            pts[1, :, 0] = 0.25  # a column of robots: the sweep's worst case, still exact
            pts[2, 5] = pts[2, 6]  # two coincident robots
        tree = lifted_tree(pts)
        d_tree, i_tree = batched_query(pts, k, tree)
        d_fast, i_fast = batched_query(pts, k)
        assert np.array_equal(d_tree, d_fast), (e, n)
        if n == 60:  # which of two coincident robots comes first (equal distances) is the tree's business
            i_tree, i_fast = np.where(i_tree == 6, 5, i_tree), np.where(i_fast == 6, 5, i_fast)
            i_tree[2, [5, 6]], i_fast[2, [5, 6]] = 0, 0
        assert np.array_equal(i_tree, i_fast), (e, n)
        for radius in (0.17, 0.5):
            want = np.asarray(tree.query_pairs(radius, output_type="ndarray"), dtype=np.int64)
            got = swarm_pairs(pts, radius)
            assert np.all(got[:, 0] < got[:, 1]) and np.all(got[:, 0] // n == got[:, 1] // n)
            assert np.array_equal(_pair_keys(want, e * n), _pair_keys(got, e * n)), (e, n, radius)
    with pytest.raises(ValueError, match="finite"):
        batched_query(np.full((2, 3, 2), np.nan), 1)


def test_a_deployed_policys_small_observations_never_import_numba() -> None:
    """drive() observes one swarm of a few robots every tick inside the sandbox: compiling a kernel there (seconds of
    CPU on the first tick) missed the script's per-tick budget (tests/envs/test_envs_train_submit.py failed so)."""
    import subprocess
    import sys

    code = """
import sys
import numpy as np
from swarmdeck.envs.scenario import View
from swarmdeck.envs.scenarios import Rendezvous
from swarmdeck.envs.batched_swarm import BatchedSwarm
sc = Rendezvous(n_agents=4)
sim = BatchedSwarm(1, 4, safety=False)
sim.set_poses(np.array([[[0.0, 0.0, 0.0], [0.5, 0.0, 1.0], [0.0, 0.5, 2.0], [-0.5, 0.0, 3.0]]]))
sim.tick(np.full((1, 4, 2), 0.05))
view = View(sim.poses, sim.points(), {}, np.zeros((1, 4, 2)), np.zeros(1, dtype=np.int64), sc.bounds)
assert sc.observe(view).shape == (1, 4, 14)
print("numba" in sys.modules)
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "False"
