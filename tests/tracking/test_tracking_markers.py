"""Tag geometry: corner order, heading convention, round trip corners ↔ poses."""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.tracking.markers import DEFAULT_REFERENCES, marker_corners, poses_from_corners


@settings(deadline=None, max_examples=60)
@given(x=st.floats(-2, 2), y=st.floats(-2, 2), th=st.floats(-np.pi + 1e-6, np.pi), size=st.floats(0.01, 0.3))
def test_corners_to_pose_round_trip(x: float, y: float, th: float, size: float) -> None:
    c = marker_corners(np.array([[x, y]]), np.array([th]), size)
    p = poses_from_corners(c)[0]
    assert np.allclose(p[:2], [x, y], atol=1e-12)
    assert abs(np.angle(np.exp(1j * (p[2] - th)))) < 1e-9
    sides = np.linalg.norm(c[0] - np.roll(c[0], 1, axis=0), axis=1)
    assert np.allclose(sides, size)


def test_corner_order_is_clockwise_seen_from_above() -> None:
    rng = np.random.default_rng(3)
    c = marker_corners(rng.normal(size=(50, 2)), rng.uniform(-np.pi, np.pi, 50), 0.08)
    # shoelace area < 0 ⇔ clockwise with y up: TL → TR → BR → BL of a tag seen from above
    x, y = c[..., 0], c[..., 1]
    area = 0.5 * np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)
    assert np.allclose(area, -0.08 ** 2)


def test_heading_zero_tag_is_upright_with_top_left_first() -> None:
    c = marker_corners(np.zeros((1, 2)), np.zeros(1), 2.0)[0]
    assert np.allclose(c, [[-1, 1], [1, 1], [1, -1], [-1, -1]])
    c90 = marker_corners(np.zeros((1, 2)), np.array([np.pi / 2]), 2.0)[0]
    # heading +90°: the tag's +x edge (TL → TR) points along arena +y
    assert np.allclose(c90[1] - c90[0], [0, 2])


def test_default_references_lie_outside_the_arena_with_distinct_ids() -> None:
    ids = [r.id for r in DEFAULT_REFERENCES]
    assert len(set(ids)) == 4 and min(ids) >= 46
    for r in DEFAULT_REFERENCES:
        c = r.corners()
        assert np.all((np.abs(c[:, 0]) > 1.6) | (np.abs(c[:, 1]) > 1.0))
