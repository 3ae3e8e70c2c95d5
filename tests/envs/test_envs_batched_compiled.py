"""BatchedSwarm.tick's compiled kernels (envs/batched_kernels.py) give the numpy pipeline's bits: the arena's
certify, wheel limits and exact unicycle step, including the rows the closed-loop equality test rarely reaches —
NaN/inf commands (that robot stops), saturated wheels (one scale per robot), turns below the series switch
(|ω·dt| < 1e-6, the Taylor branch) and headings across ±π — with the barrier off and on."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.core.compiled import AVAILABLE
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
    e, n = 3, 12
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
