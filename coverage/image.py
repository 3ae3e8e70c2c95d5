"""A static density from a grey-scale image (e.g. a letter "R", as in the paper's Fig. 1).

The image is stretched over the arena, averaged down to a ``columns`` × rows grid of square-ish
cells (rows from the arena's aspect ratio) and every cell of ink becomes a Gaussian bump at the
cell centre with σ = 0.6 · cell size and a weight chosen so that a solid region has φ ≈ 1 above
the floor. The result is a :class:`GaussianMixture` (φ_t = 0), so everything downstream
(quadrature, Jacobian, drawing, recording) treats it like any other density.
"""
from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.coverage.density import GaussianMixture

__all__ = ["image_density", "letter_image", "load_grey"]


def load_grey(path: str | Path) -> NDArray[np.uint8]:
    """Read an image file as 8-bit grey (H, W). Raises ValueError if it cannot be read."""
    p = Path(path)
    if not p.is_file():
        raise ValueError(f"image file not found: {p}")
    img = cv2.imread(str(p), cv2.IMREAD_GRAYSCALE)
    if img is None or img.size == 0:
        raise ValueError(f"cannot read {p} as an image (expected PNG, JPEG, …)")
    return img  # type: ignore[return-value]  # cv2's stubs


def letter_image(text: str = "R", height: int = 200, width: int = 320) -> NDArray[np.uint8]:
    """A grey (H, W) uint8 image: black ``text`` centred on white.

    ``text`` must be printable ASCII with at least one visible character (OpenCV's Hershey
    fonts draw anything else as "?"); raises ValueError otherwise.
    """
    if not (isinstance(text, str) and text.isascii() and text.isprintable() and text.strip()):
        raise ValueError(f"letter text must be printable ASCII with a visible character, got {text!r}")
    img = np.full((height, width), 255, dtype=np.uint8)
    font = cv2.FONT_HERSHEY_SIMPLEX
    scale = height / 30.0
    thick = max(2, height // 7)
    (tw, th), _ = cv2.getTextSize(text, font, scale, thick)
    scale *= min(0.8 * width / max(tw, 1), 0.8 * height / max(th, 1))
    (tw, th), _ = cv2.getTextSize(text, font, scale, thick)
    cv2.putText(img, text, ((width - tw) // 2, (height + th) // 2), font, scale, 0, thick, cv2.LINE_AA)
    return img


def image_density(image: str | Path | ArrayLike,
                  bounds: Bounds = DEFAULT_BOUNDS,
                  floor: float = 0.05, columns: int = 16, invert: bool = True,
                  threshold: float = 0.02) -> GaussianMixture:
    """Density from a grey image: a path, or an array (H, W) of grey values (uint8 0–255 or
    floats in [0, 1]); (H, W, 3) arrays are converted to grey.

    ``invert`` (default): dark pixels attract robots (ink on paper); otherwise bright ones.
    Cells whose ink is below ``threshold`` (0–1) get no bump. Row 0 of the image is the top
    (y_max) of the arena. Raises ValueError for unreadable or malformed images.
    """
    img = load_grey(image) if isinstance(image, (str, Path)) else np.asarray(image)
    if img.ndim == 3 and img.shape[2] in (3, 4):  # RGB(A), uint8 or floats in [0, 1]: ITU-R BT.601 luma
        rgb = img[..., :3]
        luma = rgb.astype(float) @ np.array([0.299, 0.587, 0.114])
        img = np.clip(np.round(luma), 0, 255).astype(np.uint8) if rgb.dtype == np.uint8 else luma
    if img.ndim != 2 or img.shape[0] < 2 or img.shape[1] < 2:
        raise ValueError(f"image must be a grey (H, W) array with H, W >= 2, got shape {img.shape}")
    grey = img.astype(float)
    if img.dtype == np.uint8 or grey.max() > 1.0:
        grey = grey / 255.0
    if not np.all(np.isfinite(grey)) or grey.min() < 0.0 or grey.max() > 1.0:
        raise ValueError("image values must be uint8 or floats in [0, 1]")
    if not 2 <= int(columns) <= 200:
        raise ValueError(f"columns must be in [2, 200], got {columns}")
    ink = 1.0 - grey if invert else grey
    b = Bounds.of(bounds)
    x0, x1, y0, y1 = b
    nx = int(columns)
    ny = max(2, int(round(nx * b.height / b.width)))
    small = cv2.resize(ink.astype(np.float32), (nx, ny), interpolation=cv2.INTER_AREA).astype(float)
    hx, hy = b.width / nx, b.height / ny
    sigma = 0.6 * max(hx, hy)
    row, col = np.nonzero(small > threshold)
    mu = np.column_stack([x0 + hx * (col + 0.5), y1 - hy * (row + 0.5)])
    # A lattice of Gaussians of weight w sums to ≈ w 2πσ² / (hx hy) in its interior.
    weight = small[row, col] * hx * hy / (2.0 * np.pi * sigma ** 2)
    return GaussianMixture(floor, mu, np.full(mu.shape[0], sigma), weight)
