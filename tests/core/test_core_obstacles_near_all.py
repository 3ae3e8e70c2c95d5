"""segments_near's few-robot form (every point against every segment on an (N, M) grid) gives the bits of the
gathered form it replaced (nearest_points on each (point, segment) row, then np.linalg.norm): the barrier's rows,
the simulator's contacts and validation read these distances, so the same poses must give the same numbers."""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core.graphs import DENSE_PAIRS_ROBOTS
from swarmdeck.core.obstacles import nearest_points, segments_near

coords = st.floats(-2.0, 2.0, allow_nan=False, width=64)


def gathered(p: np.ndarray, s: np.ndarray, radius: float):
    i, k = (a.ravel() for a in np.meshgrid(np.arange(len(p), dtype=np.int64), np.arange(len(s), dtype=np.int64),
                                           indexing="ij"))
    d = np.linalg.norm(p[i] - nearest_points(p[i], s[k]), axis=1)
    keep = d <= radius
    return i[keep], k[keep], d[keep]


@settings(max_examples=150, deadline=None)
@given(n=st.integers(1, DENSE_PAIRS_ROBOTS), m=st.integers(1, 9), data=st.data(),
       radius=st.floats(0.0, 1.5, allow_nan=False))
def test_the_grid_form_gives_the_gathered_forms_bits(n: int, m: int, data: st.DataObject, radius: float) -> None:
    p = np.array(data.draw(st.lists(st.tuples(coords, coords), min_size=n, max_size=n)), dtype=float)
    s = np.array(data.draw(st.lists(st.tuples(st.tuples(coords, coords), st.tuples(coords, coords)),
                                    min_size=m, max_size=m)), dtype=float)
    if data.draw(st.booleans()):  # a zero-length segment and a point exactly on an end
        s[0, 1] = s[0, 0]
        p[0] = s[-1, 1]
    if data.draw(st.booleans()) and n > 1:  # a distance exactly at the radius
        radius = float(gathered(p, s, np.inf)[2][0])
    got, want = segments_near(p, s, radius), gathered(p, s, radius)
    for g, w in zip(got, want):
        assert g.dtype == w.dtype
        np.testing.assert_array_equal(g, w)


def test_the_grid_form_on_a_known_scene() -> None:
    p = np.array([[0.0, 0.1], [1.0, 1.0], [0.5, -0.05]])
    s = np.array([[[-1.0, 0.0], [1.0, 0.0]], [[0.5, 0.5], [0.5, 0.5]]])
    i, k, d = segments_near(p, s, 0.2)
    assert i.tolist() == [0, 2] and k.tolist() == [0, 0]
    np.testing.assert_allclose(d, [0.1, 0.05])
