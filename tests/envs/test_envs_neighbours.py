"""The learning environment's neighbour queries use k-d trees: the same answers as the N×N reference, without its
memory (the old code built an (N, N, 2) difference array: 144 MB at N = 3000)."""
from __future__ import annotations

import tracemalloc

import numpy as np

import swarmdeck.envs as envs
from swarmdeck.envs.neighbours import (
    batched_min_distance,
    batched_nearest_neighbours,
    min_distance,
    nearest_neighbours,
)
from swarmdeck.envs.observations import observe


def _reference_nearest(points, k):
    d2 = np.sum((points[:, None, :] - points[None, :, :]) ** 2, axis=-1)
    np.fill_diagonal(d2, np.inf)
    return np.argsort(d2, axis=1, kind="stable")[:, :k]


def _reference_min(points):
    d = np.linalg.norm(points[:, None] - points[None], axis=-1)
    np.fill_diagonal(d, np.inf)
    return float(d.min())


def test_nearest_and_min_distance_match_the_dense_reference():
    rng = np.random.default_rng(3)
    for n, k in ((2, 1), (7, 3), (50, 6), (300, 10)):
        pts = rng.uniform(-1.5, 1.5, (n, 2))
        assert np.array_equal(nearest_neighbours(pts, k), _reference_nearest(pts, k))
        assert min_distance(pts) == _reference_min(pts)
    assert min_distance(np.zeros((1, 2))) == float("inf")


def test_batched_queries_stay_within_each_swarm_and_match_one_swarm_at_a_time():
    rng = np.random.default_rng(4)
    pts = rng.uniform(-1.5, 1.5, (5, 40, 2))
    pts[3] = pts[2] + 1e-9  # two swarms almost on top of each other: still never mixed
    idx = batched_nearest_neighbours(pts, 4)
    dmin = batched_min_distance(pts)
    for e in range(5):
        assert np.array_equal(idx[e], _reference_nearest(pts[e], 4))
        assert dmin[e] == _reference_min(pts[e])


def test_observations_and_infos_at_3000_robots_need_no_n_by_n_array():
    rng = np.random.default_rng(5)
    n = 3000
    pts = rng.uniform(-10, 10, (n, 2))
    poses = np.column_stack((pts, rng.uniform(-np.pi, np.pi, n)))
    tracemalloc.start()
    try:
        observe(poses, pts, (-10.0, 10.0, -10.0, 10.0), 6)
        min_distance(pts)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 20e6, f"peak {peak / 1e6:.0f} MB: an N x N array came back"


def test_the_environment_reports_the_same_minimum_distance():
    env = envs.parallel_env(n_robots=8, task="rendezvous", safety=False, max_steps=3)
    env.reset(seed=2)
    _, _, _, _, infos = env.step({a: np.zeros(2, np.float32) for a in env.agents})
    from swarmdeck.core.kinematics import lookahead_points

    pts = lookahead_points(env.arena.poses(), env.params.lookahead)
    assert infos["robot_0"]["min_distance"] == _reference_min(pts)
