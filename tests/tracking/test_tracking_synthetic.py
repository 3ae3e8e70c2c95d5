"""The synthetic overhead camera: exact truth, keystone from tilt, the projected density, and
the robot bodies drawn where the truth says."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.tracking import SyntheticCameraConfig, SyntheticRenderer
from swarmdeck.tracking.camera_model import overhead_camera


@pytest.fixture(scope="module")
def clean() -> SyntheticRenderer:
    """No noise, no JPEG, no vignetting: pixel values can be compared directly."""
    return SyntheticRenderer(SyntheticCameraConfig(noise_sigma=0.0, jpeg_quality=None, vignetting=0.0))


def test_camera_projects_arena_centre_near_image_centre_and_tilt_makes_keystone() -> None:
    cam = overhead_camera((1280, 720), 2.6, 0.2, np.pi / 2, 0.0, (0.0, 0.0), (-1.8, 1.8, -1.2, 1.2), np.zeros(5))
    px = cam.project(np.array([[0.0, 0.0, 0.0]]))[0]
    assert np.allclose(px, [639.5, 359.5], atol=1e-6)
    far = cam.project(np.array([[-1.0, 1.0, 0.0], [1.0, 1.0, 0.0]]))        # tilted towards +y
    near = cam.project(np.array([[-1.0, -1.0, 0.0], [1.0, -1.0, 0.0]]))
    assert np.ptp(far[:, 0]) < np.ptp(near[:, 0])                           # far edge shorter
    assert far[0, 1] < near[0, 1]                                          # +y is up in the image


def test_truth_corners_match_the_rendered_tag(clean) -> None:
    """The darkest pixels of a lone tag sit inside its truth quadrilateral."""
    f = clean.render([7], np.array([[0.3, -0.2, 0.4]]))
    q = f.tag_corners_px[0]
    grey = f.image.mean(axis=2)
    x0, y0 = np.floor(q.min(axis=0)).astype(int) - 6
    x1, y1 = np.ceil(q.max(axis=0)).astype(int) + 6
    dark = np.argwhere(grey[y0:y1, x0:x1] < 60) + [y0, x0]                 # (row, col)
    assert len(dark) > 50
    centre = q.mean(axis=0)
    assert np.allclose(dark[:, ::-1].mean(axis=0), centre, atol=3.0)
    side = np.linalg.norm(q[1] - q[0])
    assert np.max(np.abs(dark[:, ::-1] - centre)) < 0.75 * side


def test_density_image_is_projected_on_the_floor(clean) -> None:
    h, w = 40, 64
    density = np.zeros((h, w, 3), np.uint8)
    density[:, : w // 2] = (255, 40, 40)                                   # left half of the arena red
    density[:, w // 2:] = (255, 255, 255)
    plain = clean.render([], np.zeros((0, 3))).image.astype(float)
    lit = clean.render([], np.zeros((0, 3)), density=density).image.astype(float)
    cam = clean.camera
    left = np.round(cam.project(np.array([[-0.8, 0.3, 0.0]]))[0]).astype(int)
    right = np.round(cam.project(np.array([[0.8, 0.3, 0.0]]))[0]).astype(int)
    outside = np.round(cam.project(np.array([[0.0, 1.15, 0.0]]))[0]).astype(int)
    dl = lit[left[1], left[0]] - plain[left[1], left[0]]
    assert dl[0] > -5 and dl[1] < -30 and dl[2] < -30                      # green and blue dimmed
    assert np.allclose(lit[right[1], right[0]], plain[right[1], right[0]], atol=3)
    assert np.allclose(lit[outside[1], outside[0]], plain[outside[1], outside[0]], atol=3)


def test_robot_body_is_drawn_at_tag_height(clean) -> None:
    """With the camera off-centre, a robot top lands where its tag-height projection says,
    not where its floor projection says (parallax is rendered)."""
    pose = np.array([[1.3, 0.8, 0.0]])
    f = clean.render([3], pose)
    cfg = clean.config
    top = clean.camera.project(np.array([[1.3, 0.8 + 0.9 * cfg.body_radius, cfg.tag_height]]))[0]
    floor = clean.camera.project(np.array([[1.3, 0.8 + 0.9 * cfg.body_radius, 0.0]]))[0]
    assert np.linalg.norm(top - floor) > 3.0
    grey = f.image.mean(axis=2)
    at = grey[int(round(top[1])), int(round(top[0]))]
    plain = clean.render([], np.zeros((0, 3))).image.mean(axis=2)
    assert abs(at - plain[int(round(top[1])), int(round(top[0]))]) > 20     # something drawn there


def test_density_image_rasterises_a_callable_with_its_peak_coloured() -> None:
    from swarmdeck.tracking import density_image

    def bump(q: np.ndarray) -> np.ndarray:
        return np.exp(-np.sum((q - [1.0, 0.5]) ** 2, axis=1) / 0.05)

    img = density_image(bump, (-1.6, 1.6, -1.0, 1.0), (100, 160), rgb=(255, 0, 0))
    assert img.shape == (100, 160, 3) and img.dtype == np.uint8
    peak = np.unravel_index(np.argmin(img[..., 1].astype(int)), img.shape[:2])
    # pixel centre of the peak ≈ (1.0, 0.5): col = (1.0 + 1.6) / 0.02, row = (1.0 − 0.5) / 0.02
    assert abs(peak[1] - 130) <= 1 and abs(peak[0] - 25) <= 1
    assert tuple(img[99, 0]) == (255, 255, 255)
    flat = density_image(lambda q: np.ones(len(q)))
    assert np.all(flat == 255)
