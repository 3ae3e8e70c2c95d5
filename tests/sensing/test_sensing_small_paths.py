"""The numpy paths of the ToF geometry for rps-sized runs give the compiled paths' bits (issue 28: an rps 2.x script
reading its distance sensors imports neither numba nor scipy).

Up to ``DENSE_PAIRS_ROBOTS`` robots :func:`cast_sensor_rays` tests every sensor of every pair within reach in numpy,
and up to ``SMALL_RAY_SEGMENTS`` (ray, segment) pairs :func:`ray_segments` takes its numpy form; both are compared
here, bit for bit, with the compiled kernels (``sensing.kernels``, which ran before at every size): random floors,
bodies overlapping (origins inside a body read 0), rays grazing a body, bodies whose near side lies at the sensors'
range (the cut-off at ``max_range``), segments touched at an end, parallel to a ray, or through a ray's origin.
"""
from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core.constants import ROBOT_RADIUS, TOF_BODY_OFFSET, TOF_RANGE
from swarmdeck.core.graphs import DENSE_PAIRS_ROBOTS
from swarmdeck.sensing import DistanceSensorConfig, geometry, sensor_rays
from swarmdeck.sensing.geometry import cast_sensor_rays, ray_segments
from swarmdeck.sensing.models import body_centres

CFG = DistanceSensorConfig()


@contextmanager
def _compiled_paths() -> Iterator[None]:
    """The paths every size took before: the k-d tree's pairs and numba's kernels."""
    saved = geometry.DENSE_PAIRS_ROBOTS, geometry.SMALL_RAY_SEGMENTS
    geometry.DENSE_PAIRS_ROBOTS, geometry.SMALL_RAY_SEGMENTS = 1, -1
    try:
        yield
    finally:
        geometry.DENSE_PAIRS_ROBOTS, geometry.SMALL_RAY_SEGMENTS = saved


def _cast(poses: np.ndarray) -> np.ndarray:
    origins, directions = sensor_rays(poses, CFG)
    return cast_sensor_rays(body_centres(poses, CFG.body_offset), poses[:, 2], origins, directions,
                            CFG.pose_array()[:, 2], CFG.max_range, CFG.body_radius)


def _place(poses: np.ndarray, i: int, sensor: int, j: int, kind: str, nudge: float) -> np.ndarray:
    """``poses`` with robot j moved so that its body meets robot i's ``sensor`` ray as ``kind`` says: ``graze``
    (tangent), ``range`` (its near side at the sensors' range), ``inside`` (the ray's origin inside j's body);
    ``nudge`` m moves it a little off that case."""
    origins, directions = sensor_rays(poses, CFG)
    o, u = origins[i, sensor], directions[i, sensor]
    normal = np.array([-u[1], u[0]])
    if kind == "graze":
        centre = o + 0.3 * u + (ROBOT_RADIUS + nudge) * normal
    elif kind == "range":
        centre = o + (TOF_RANGE + ROBOT_RADIUS + nudge) * u
    else:
        centre = o + (0.5 * ROBOT_RADIUS + nudge) * u
    theta = poses[j, 2]
    out = poses.copy()
    out[j, :2] = centre - TOF_BODY_OFFSET * np.array([math.cos(theta), math.sin(theta)])
    return out


NUDGES = st.sampled_from([0.0, 1e-15, -1e-15, 1e-12, -1e-12, 1e-9])


@settings(max_examples=60, deadline=None)
@given(n=st.integers(2, DENSE_PAIRS_ROBOTS), seed=st.integers(0, 2**31 - 1), spread=st.floats(0.02, 2.0),
       cases=st.lists(st.tuples(st.sampled_from(["graze", "range", "inside"]), st.integers(0, 6), NUDGES),
                      max_size=3))
def test_a_few_robots_sensor_rays_have_the_compiled_paths_bits(n, seed, spread, cases):
    rng = np.random.default_rng(seed)
    poses = np.column_stack((rng.uniform(-spread, spread, (n, 2)), rng.uniform(-math.pi, math.pi, n)))
    for c, (kind, sensor, nudge) in enumerate(cases):
        i, j = c % n, (c + 1) % n
        poses = _place(poses, i, sensor, j, kind, nudge)
    dense = _cast(poses)
    with _compiled_paths():
        compiled = _cast(poses)
    assert dense.shape == (n, CFG.n_sensors)
    assert np.array_equal(dense, compiled), (dense, compiled)


def test_the_constructed_cases_are_what_they_say():
    """The boundary cases above do reach the branches they are named for (0 inside a body, a hit at the range)."""
    poses = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 0.0]])
    inside = _cast(_place(poses, 0, 3, 1, "inside", 0.0))
    assert inside[0, 3] == 0.0
    at_range = _cast(_place(poses, 0, 3, 1, "range", -1e-9))
    assert math.isclose(at_range[0, 3], TOF_RANGE, abs_tol=1e-8)
    beyond = _cast(_place(poses, 0, 3, 1, "range", 1e-9))
    assert math.isinf(beyond[0, 3])


@st.composite
def _rays_and_segments(draw: st.DrawFn) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rays (R, 2) origins and unit directions, segments (M, 2, 2) with R·M ≤ SMALL_RAY_SEGMENTS; some segments
    through a ray's origin, touched at an end, or parallel to a ray."""
    r = draw(st.integers(1, 84))
    m = draw(st.integers(1, min(48, geometry.SMALL_RAY_SEGMENTS // r)))
    rng = np.random.default_rng(draw(st.integers(0, 2**31 - 1)))
    origins = rng.uniform(-1.5, 1.5, (r, 2))
    angle = rng.uniform(-math.pi, math.pi, r)
    directions = np.column_stack((np.cos(angle), np.sin(angle)))
    segments = rng.uniform(-1.5, 1.5, (m, 2, 2))
    for s in range(min(m, draw(st.integers(0, 4)))):
        k = s % r
        length = rng.uniform(0.0, 2.0)
        kind = s % 3
        if kind == 0:  # an end on the ray
            segments[s, 0] = origins[k] + length * directions[k]
        elif kind == 1:  # parallel to the ray, off it
            segments[s, 0] = origins[k] + np.array([-directions[k, 1], directions[k, 0]]) * 0.1
            segments[s, 1] = segments[s, 0] + length * directions[k]
        else:  # through the ray's origin
            segments[s, 0] = origins[k] - 0.2 * np.array([-directions[k, 1], directions[k, 0]])
            segments[s, 1] = origins[k] + 0.2 * np.array([-directions[k, 1], directions[k, 0]])
    return origins, directions, segments


@settings(max_examples=60, deadline=None)
@given(case=_rays_and_segments())
def test_few_rays_against_few_segments_have_the_compiled_paths_bits(case):
    origins, directions, segments = case
    small = ray_segments(origins, directions, segments)
    with _compiled_paths():
        compiled = ray_segments(origins, directions, segments)
    assert np.array_equal(small, compiled), (small, compiled)
