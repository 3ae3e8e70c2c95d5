"""The ToF rays' geometry against closed-form cases: a robot facing a wall at a known distance, a robot behind
another (occluded), grazing angles, the robot's own body, and the staged k-d tree against a brute force."""
from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.core.constants import ROBOT_RADIUS, TOF_BODY_OFFSET, TOF_RANGE
from swarmdeck.sensing import DistanceSensorConfig, cast_rays, sensor_rays, true_distances
from swarmdeck.sensing.geometry import ray_circles

FRONT, LEFT, RIGHT, FRONT_LEFT = 3, 1, 5, 2  # indices into the seven Robotarium 2.0 sensors


def test_a_robot_facing_a_wall_reads_the_distance_from_its_front_sensor():
    cfg = DistanceSensorConfig()
    wall = np.array([[[0.5, -0.8], [0.5, 0.8]]])
    d = true_distances(np.array([[0.0, 0.0, 0.0]]), cfg, obstacles=wall)
    front_x = TOF_BODY_OFFSET + 0.05  # the front sensor sits 5 cm ahead of the body centre
    assert math.isclose(d[0, FRONT], 0.5 - front_x, abs_tol=1e-12)
    # the ±45° sensors meet the same wall at (0.5 − x)/cos 45°
    x45 = TOF_BODY_OFFSET + 0.04
    assert math.isclose(d[0, FRONT_LEFT], (0.5 - x45) * math.sqrt(2), rel_tol=1e-12)
    assert math.isclose(d[0, 4], (0.5 - x45) * math.sqrt(2), rel_tol=1e-12)
    # the sideways and backward sensors see nothing (an open floor: rps 2.0's walls do not stop rays)
    assert np.isinf(d[0, [0, LEFT, RIGHT, 6]]).all()


def test_walls_stop_rays_when_configured():
    cfg = DistanceSensorConfig(walls=True)
    x0, x1, y0, y1 = DEFAULT_BOUNDS
    pose = np.array([[x1 - 0.3, 0.0, 0.0]])
    d = true_distances(pose, cfg, bounds=DEFAULT_BOUNDS)
    assert math.isclose(d[0, FRONT], 0.3 - TOF_BODY_OFFSET - 0.05, abs_tol=1e-12)
    # facing up near the top wall: the front sensor reads the gap to y_max
    d = true_distances(np.array([[0.0, y1 - 0.2, math.pi / 2]]), cfg, bounds=DEFAULT_BOUNDS)
    assert math.isclose(d[0, FRONT], 0.2 - TOF_BODY_OFFSET - 0.05, abs_tol=1e-12)


def test_a_robot_behind_another_is_occluded():
    cfg = DistanceSensorConfig()
    poses = np.array([[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [0.6, 0.0, 0.0]])
    d = true_distances(poses, cfg)
    # robot 0's front ray meets robot 1's body (centred TOF_BODY_OFFSET ahead of its axle), not robot 2
    expected = (0.3 + TOF_BODY_OFFSET) - ROBOT_RADIUS - (TOF_BODY_OFFSET + 0.05)
    assert math.isclose(d[0, FRONT], expected, abs_tol=1e-12)
    # robot 2's back-left sensor (at heading π) sees robot 1
    assert math.isfinite(d[2, 0]) and d[2, 0] < 0.3


def test_a_ray_never_hits_its_own_body():
    cfg = DistanceSensorConfig()
    d = true_distances(np.array([[0.0, 0.0, 1.0]]), cfg)
    assert np.isinf(d).all()


def test_grazing_a_segment_at_a_shallow_angle_and_running_parallel():
    origin = np.zeros((1, 2))
    alpha, h = 1e-3, 1e-3
    seg = np.array([[[-1.0, h], [2.0, h]]])
    t = cast_rays(origin, np.array([[math.cos(alpha), math.sin(alpha)]]), 1.2, segments=seg)
    assert math.isclose(t[0], h / math.sin(alpha), rel_tol=1e-9)
    # parallel to the segment: no crossing point (as rps 2.0)
    assert np.isinf(cast_rays(origin, np.array([[1.0, 0.0]]), 1.2, segments=seg)).all()
    # beyond the range: nothing
    assert np.isinf(cast_rays(origin, np.array([[math.cos(alpha / 2), math.sin(alpha / 2)]]), 1.2, segments=seg)).all()
    # the ray through a segment's end point hits it
    end = np.array([[[0.5, -0.5], [0.5, 0.0]]])
    assert cast_rays(origin, np.array([[1.0, 0.0]]), 1.2, segments=end)[0] == 0.5


def test_grazing_a_body_tangent():
    r = ROBOT_RADIUS
    centre = np.array([[0.5, r - 1e-9]])
    t = cast_rays(np.zeros((1, 2)), np.array([[1.0, 0.0]]), 1.2, centres=centre, radius=r)
    assert math.isclose(t[0], 0.5 - math.sqrt(r * r - (r - 1e-9) ** 2), abs_tol=1e-9)
    miss = cast_rays(np.zeros((1, 2)), np.array([[1.0, 0.0]]), 1.2, centres=np.array([[0.5, r + 1e-9]]), radius=r)
    assert np.isinf(miss).all()


def test_the_endpoints_of_the_rays_are_where_the_sensors_are():
    cfg = DistanceSensorConfig()
    origins, dirs = sensor_rays(np.array([[1.0, -0.5, math.pi / 2]]), cfg)
    assert np.allclose(origins[0, FRONT], [1.0, -0.5 + TOF_BODY_OFFSET + 0.05])
    assert np.allclose(dirs[0, FRONT], [0.0, 1.0])
    assert np.allclose(np.linalg.norm(dirs, axis=-1), 1.0)


def _brute(origins, dirs, max_range, centres, radius, owners):
    r = len(origins)
    rays = np.repeat(np.arange(r), len(centres))
    circles = np.tile(np.arange(len(centres)), r)
    t = ray_circles(origins, dirs, rays, centres, circles, radius)
    t[owners[rays] == circles] = np.inf
    best = t.reshape(r, len(centres)).min(axis=1)
    best[best > max_range] = np.inf
    return best


@settings(max_examples=40)
@given(n=st.integers(2, 60), seed=st.integers(0, 2**31 - 1), spread=st.floats(0.3, 3.0))
def test_the_staged_tree_finds_the_same_first_hits_as_a_brute_force(n, seed, spread):
    rng = np.random.default_rng(seed)
    poses = np.column_stack((rng.uniform(-spread, spread, (n, 2)), rng.uniform(-math.pi, math.pi, n)))
    cfg = DistanceSensorConfig()
    origins, dirs = sensor_rays(poses, cfg)
    o, u = origins.reshape(-1, 2), dirs.reshape(-1, 2)
    owners = np.repeat(np.arange(n), cfg.n_sensors)
    centres = poses[:, :2] + TOF_BODY_OFFSET * np.column_stack((np.cos(poses[:, 2]), np.sin(poses[:, 2])))
    got = cast_rays(o, u, TOF_RANGE, centres=centres, radius=ROBOT_RADIUS, owners=owners)
    assert np.array_equal(got, _brute(o, u, TOF_RANGE, centres, ROBOT_RADIUS, owners))


@settings(max_examples=30)
@given(n=st.integers(2, 80), seed=st.integers(0, 2**31 - 1), spread=st.floats(0.3, 3.0), m=st.integers(0, 6))
def test_the_sensor_rays_compiled_and_numpy_paths_match_a_brute_force(n, seed, spread, m):
    from swarmdeck.sensing import kernels

    rng = np.random.default_rng(seed)
    poses = np.column_stack((rng.uniform(-spread, spread, (n, 2)), rng.uniform(-math.pi, math.pi, n)))
    segs = rng.uniform(-spread, spread, (m, 2, 2))
    cfg = DistanceSensorConfig()
    origins, dirs = sensor_rays(poses, cfg)
    o, u = origins.reshape(-1, 2), dirs.reshape(-1, 2)
    owners = np.repeat(np.arange(n), cfg.n_sensors)
    centres = poses[:, :2] + TOF_BODY_OFFSET * np.column_stack((np.cos(poses[:, 2]), np.sin(poses[:, 2])))
    expected = _brute(o, u, TOF_RANGE, centres, ROBOT_RADIUS, owners)
    expected = np.minimum(expected, cast_rays(o, u, TOF_RANGE, segments=segs)).reshape(n, -1)
    compiled = true_distances(poses, cfg, obstacles=segs)
    saved = kernels.AVAILABLE
    kernels.AVAILABLE = False
    try:
        plain = true_distances(poses, cfg, obstacles=segs)
    finally:
        kernels.AVAILABLE = saved
    for got in (compiled, plain):
        assert np.array_equal(np.isinf(got), np.isinf(expected))
        fin = np.isfinite(expected)
        np.testing.assert_allclose(got[fin], expected[fin], rtol=0, atol=1e-12)
