"""A static density from a grey-scale image (the paper's "R")."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from swarmdeck.coverage import CoverageConfig, CoverageController, GaussianMixture, image_density, letter_image

BOUNDS = (-1.6, 1.6, -1.0, 1.0)


def _pixel_to_arena(row, col, shape):
    h, w = shape
    return np.array([BOUNDS[0] + (col + 0.5) / w * 3.2, BOUNDS[3] - (row + 0.5) / h * 2.0])


def test_ink_attracts_and_paper_does_not(tmp_path):
    img = letter_image("R", 200, 320)
    path = tmp_path / "r.png"
    assert cv2.imwrite(str(path), img)
    g = image_density(path, BOUNDS, floor=0.05, columns=24)
    assert isinstance(g, GaussianMixture) and g.n_bumps > 10
    ink = np.argwhere(cv2.erode(255 - img, np.ones((15, 15), np.uint8)) > 200)
    paper = np.argwhere(cv2.erode(img, np.ones((25, 25), np.uint8)) > 250)
    q_ink = np.array([_pixel_to_arena(r, c, img.shape) for r, c in ink[::97]])
    q_paper = np.array([_pixel_to_arena(r, c, img.shape) for r, c in paper[::397]])
    assert g.evaluate(q_ink).min() > 0.4
    assert g.evaluate(q_paper).max() < 0.15
    np.testing.assert_array_equal(g.evaluate_dt(q_ink), 0.0)
    # bright-on-dark with invert=False gives the same density as the inverted image
    g2 = image_density(255 - img, BOUNDS, floor=0.05, columns=24, invert=False)
    np.testing.assert_allclose(g2.evaluate(q_ink), g.evaluate(q_ink), rtol=1e-6)


def test_solid_ink_is_one_above_the_floor():
    img = np.full((100, 160), 255, np.uint8)
    img[:, :80] = 0                                     # left half black
    g = image_density(img, BOUNDS, floor=0.05, columns=32)
    q = np.array([[-1.0, 0.0], [-0.8, 0.5], [-1.2, -0.4]])
    np.testing.assert_allclose(g.evaluate(q), 1.05, atol=0.02)
    np.testing.assert_allclose(g.evaluate(-q), 0.05, atol=1e-6)


def test_controller_drives_robots_onto_the_letter():
    g = image_density(letter_image("R"), BOUNDS, columns=12)
    rng = np.random.default_rng(3)
    p = p0 = rng.uniform([-1.5, -0.9], [1.5, 0.9], (20, 2))
    ctrl = CoverageController(CoverageConfig(law="lloyd", max_speed=None), g)
    h0 = None
    for _k in range(12):                         # discrete Lloyd: p ← c
        _, st = ctrl(p, 0.0)
        h0 = st.cost_H if h0 is None else h0
        p = st.centroids.copy()
    assert st.cost_H < 0.8 * h0
    assert np.mean(g.evaluate(p) > 0.3) > 1.4 * np.mean(g.evaluate(p0) > 0.3)


@pytest.mark.parametrize("bad", ["missing.png", "not-an-image.png"])
def test_unreadable_image_is_a_clear_error(bad, tmp_path):
    path = tmp_path / bad
    if bad == "not-an-image.png":
        path.write_text("hello")
    with pytest.raises(ValueError, match="image"):
        image_density(path)


@pytest.mark.parametrize("arr", [np.zeros((1, 5)), np.zeros((4, 4, 2)), np.full((4, 4), 2.0) * -1])
def test_malformed_arrays_are_clear_errors(arr):
    with pytest.raises(ValueError):
        image_density(arr)


def test_blank_image_with_floor_is_uniform_and_without_floor_has_no_mass():
    g = image_density(np.full((20, 30), 255, np.uint8), BOUNDS, floor=0.1)
    assert g.n_bumps == 0
    with pytest.raises(ValueError, match="zero mass"):
        image_density(np.full((20, 30), 255, np.uint8), BOUNDS, floor=0.0)


def test_float_rgb_images_are_grey_not_cast_to_uint8():
    import numpy as np

    from swarmdeck.coverage import image_density

    grey = np.ones((40, 64))
    grey[10:30, 20:40] = 0.0  # a dark square on white, floats in [0, 1]
    rgb = np.repeat(grey[..., None], 3, axis=2)
    a, b = image_density(grey), image_density(rgb)
    assert np.allclose(a.mu, b.mu) and np.allclose(a.weight, b.weight)
    c = image_density((rgb * 255).astype(np.uint8))
    assert np.allclose(a.mu, c.mu) and np.allclose(a.weight, c.weight)


@pytest.mark.parametrize("text", ["Ω", " ", "", "R\n", "é"])
def test_letters_opencv_cannot_draw_are_errors(text):
    from swarmdeck.coverage import letter_image

    with pytest.raises(ValueError, match="printable ASCII"):
        letter_image(text)
