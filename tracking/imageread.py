"""The one image-file reader of swarmdeck's tracking (image-folder camera, ``swarmdeck
calibrate camera`` and ``calibrate arena``).

``read_image(path)`` → (H, W, 3) RGB uint8, whatever the file holds: 8- or 16-bit,
grey, grey + alpha, colour or colour + alpha, integer or float (TIFF/EXR-style floats are
taken as 0..1 and clipped; NaN → 0). EXIF orientation is applied (a phone photo
shows as the phone showed it). 16-bit samples become 8-bit by v/257, rounded.
"""
from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from swarmdeck.core.errors import SwarmdeckError

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp")

# ANYDEPTH keeps 16-bit/float samples; ANYCOLOR keeps grey as grey. Unlike IMREAD_UNCHANGED,
# this combination applies EXIF orientation (OpenCV ignores it only for UNCHANGED).
_FLAGS = cv2.IMREAD_ANYDEPTH | cv2.IMREAD_ANYCOLOR


class ImageReadError(ValueError, SwarmdeckError):
    """An image file that cannot be read (the message names the file and why)."""


def to_uint8(image: np.ndarray) -> np.ndarray:
    """uint8 as is; uint16 → round(v/257); other integers clipped to 0..255; floats as
    0..1 → round(255 v) clipped (NaN → 0)."""
    if image.dtype == np.uint8:
        return image
    if image.dtype == np.uint16:
        return ((image.astype(np.uint32) + 128) // 257).astype(np.uint8)
    if np.issubdtype(image.dtype, np.integer):
        return np.clip(image, 0, 255).astype(np.uint8)
    f = np.nan_to_num(image.astype(np.float64), nan=0.0, posinf=1.0, neginf=0.0)
    return np.round(np.clip(f, 0.0, 1.0) * 255.0).astype(np.uint8)


def decoded_to_rgb(image: np.ndarray) -> np.ndarray | None:
    """An image as OpenCV decodes it (BGR, BGRA, grey, grey + alpha; any depth) → RGB
    uint8, or None when it is not an image."""
    if not isinstance(image, np.ndarray) or image.size == 0:
        return None
    img = to_uint8(image)
    if img.ndim == 3 and img.shape[2] == 1:
        img = img[..., 0]
    if img.ndim == 2:
        return cv2.cvtColor(img, cv2.COLOR_GRAY2RGB)
    if img.ndim == 3 and img.shape[2] == 2:  # grey + alpha
        return cv2.cvtColor(np.ascontiguousarray(img[..., 0]), cv2.COLOR_GRAY2RGB)
    if img.ndim == 3 and img.shape[2] == 3:
        return cv2.cvtColor(img, cv2.COLOR_BGR2RGB)
    if img.ndim == 3 and img.shape[2] == 4:
        return cv2.cvtColor(img, cv2.COLOR_BGRA2RGB)
    return None


def read_image(path: str | Path) -> np.ndarray:
    """The image file at ``path`` as (H, W, 3) RGB uint8 with EXIF orientation applied.

    Raises:
        ImageReadError: naming the file: missing, unreadable, or not an image OpenCV decodes.
    """
    p = Path(path)
    try:
        data = np.fromfile(p, dtype=np.uint8)  # not cv2.imread: non-ASCII paths, no stderr warnings
    except FileNotFoundError:
        raise ImageReadError(f"{p}: no such file") from None
    except OSError as exc:
        raise ImageReadError(f"{p}: cannot read: {exc.strerror or exc}") from None
    if data.size == 0:
        raise ImageReadError(f"{p}: empty file")
    try:
        decoded = cv2.imdecode(data, _FLAGS)
    except cv2.error as exc:
        raise ImageReadError(f"{p}: OpenCV cannot decode it: {exc.err}") from None
    rgb = decoded_to_rgb(decoded) if decoded is not None else None
    if rgb is None:
        raise ImageReadError(f"{p}: not an image OpenCV can decode ({', '.join(IMAGE_SUFFIXES)})")
    return rgb
