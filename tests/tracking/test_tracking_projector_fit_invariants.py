"""Invariants of the projector fit (hypothesis): for any projector pose that sees the arena, exact corners give back
its homography (to a micrometre on the floor), the error reported is zero, and the homography is accepted; the
same homography with the arena pushed off its image is refused."""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.tracking.homography import apply_homography
from swarmdeck.tracking.projector import (
    SyntheticProjector,
    check_projector_homography,
    fit_projector,
    homography_error_mm,
    marker_pattern,
)

PATTERN = marker_pattern((1280, 800))

poses = st.builds(SyntheticProjector,
                  height_m=st.floats(1.8, 3.5), tilt=st.floats(0.0, 0.35), tilt_azimuth=st.floats(-np.pi, np.pi),
                  roll=st.floats(-0.2, 0.2), look_at=st.tuples(st.floats(-0.2, 0.2), st.floats(-0.2, 0.2)))


@settings(max_examples=40)
@given(proj=poses)
def test_exact_corners_give_back_the_homography(proj):
    H = proj.homography()
    assert check_projector_homography(H, DEFAULT_BOUNDS, proj.size) is None
    floor = apply_homography(np.linalg.inv(H), PATTERN.corners_px)
    fit = fit_projector(floor, PATTERN.corners_px, DEFAULT_BOUNDS, proj.size)
    assert fit.ok and fit.H is not None, fit.reason
    assert fit.rms_mm < 1e-3 and fit.n_inliers == PATTERN.corners_px.size // 2
    assert homography_error_mm(fit.H, H, DEFAULT_BOUNDS) < 1e-3


@settings(max_examples=40)
@given(proj=poses, shift=st.floats(1.2, 50.0), axis=st.sampled_from([0, 1]), sign=st.sampled_from([-1.0, 1.0]))
def test_a_homography_that_puts_the_arena_off_the_image_is_refused(proj, shift, axis, sign):
    T = np.eye(3)
    T[axis, 2] = sign * shift * proj.size[axis]  # move the image by more than its own width / height
    reason = check_projector_homography(T @ proj.homography(), DEFAULT_BOUNDS, proj.size)
    assert reason is not None and "off the projector image" in reason
