"""Floor homography: exact fits, rejection rules, camera centre and parallax in closed form."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.tracking.camera_model import overhead_camera
from swarmdeck.tracking.homography import (
    apply_homography,
    camera_centre_from_homography,
    correct_parallax,
    fit_floor_homography,
)
from swarmdeck.tracking.markers import DEFAULT_REFERENCES, reference_corners


@pytest.fixture(scope="module")
def camera():
    return overhead_camera((1280, 720), 2.6, 0.15, 0.7, 0.05, (0.1, -0.05), (-1.8, 1.8, -1.2, 1.2), np.zeros(5))


def _ref_pixels(camera, z: float = 0.0):
    ids, arena = reference_corners(DEFAULT_REFERENCES)
    px = camera.project(np.concatenate([arena, np.full(arena.shape[:2] + (1,), z)], axis=2).reshape(-1, 3))
    return arena, px.reshape(-1, 4, 2)


def test_exact_correspondences_give_the_plane_homography(camera) -> None:
    arena, px = _ref_pixels(camera)
    fit = fit_floor_homography(px, arena, camera.size)
    assert fit.ok and fit.rms_m < 1e-6 and fit.n_references == 4
    H_true = np.linalg.inv(camera.K @ camera.plane_homography(0.0))
    probe = np.array([[100.0, 50.0], [640.0, 360.0], [1200.0, 700.0]])
    assert np.allclose(apply_homography(fit.H, probe), apply_homography(H_true, probe), atol=1e-6)


def test_camera_centre_recovered_from_homography(camera) -> None:
    arena, px = _ref_pixels(camera)
    fit = fit_floor_homography(px, arena, camera.size)
    C = camera_centre_from_homography(fit.H, camera.K)
    assert np.allclose(C, camera.centre, atol=1e-5)


def test_parallax_correction_matches_projection(camera) -> None:
    """A point at height h, mapped by the floor homography, lands where its ray meets the floor;
    the correction brings it back to its true (x, y)."""
    arena, px = _ref_pixels(camera)
    H = fit_floor_homography(px, arena, camera.size).H
    rng = np.random.default_rng(0)
    h = 0.06
    truth = rng.uniform([-1.5, -0.9], [1.5, 0.9], (30, 2))
    seen = apply_homography(H, camera.project(np.column_stack([truth, np.full(30, h)])))
    assert np.max(np.linalg.norm(seen - truth, axis=1)) > 0.02          # parallax is cm-sized
    fixed = correct_parallax(seen, camera.centre, h)
    assert np.allclose(fixed, truth, atol=1e-9)
    # directly below the camera nothing moves
    assert np.allclose(correct_parallax(camera.centre[:2], camera.centre, h), camera.centre[:2])


def test_rejects_too_few_references(camera) -> None:
    arena, px = _ref_pixels(camera)
    fit = fit_floor_homography(px[:2], arena[:2], camera.size, min_references=3)
    assert not fit.ok and "2 reference marker(s) visible, need 3" in fit.reason


def test_rejects_inconsistent_reference_corners(camera) -> None:
    arena, px = _ref_pixels(camera)
    bad = px.copy()
    bad[0, 2] += [12.0, 9.0]                                              # one corner misdetected by 15 px
    fit = fit_floor_homography(bad, arena, camera.size)
    assert not fit.ok and "misdetected" in fit.reason
    assert fit_floor_homography(px, arena, camera.size).ok


def test_rejects_mirrored_and_ill_conditioned(camera) -> None:
    arena, px = _ref_pixels(camera)
    mirrored = arena * [1, -1]
    fit = fit_floor_homography(px, mirrored[:, [1, 0, 3, 2]], camera.size, max_rms_m=1.0)
    assert not fit.ok and "handedness" in fit.reason
    squashed = px.copy()
    squashed[..., 1] = 360 + (squashed[..., 1] - 360) * 0.01              # image collapsed to a line
    fit = fit_floor_homography(squashed, arena, camera.size, max_rms_m=1.0)
    assert not fit.ok and "ill-conditioned" in fit.reason
