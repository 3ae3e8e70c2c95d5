"""Small raster helpers for the synthetic camera: marker images, anti-aliased placement.

Texture convention: texel (col, row) centre ↔ plane point ``origin + (col, row)·texel`` in the
texture's own plane frame (callers choose whether row runs along +y or −y).
"""
from __future__ import annotations

import cv2
import numpy as np

from swarmdeck.tracking.dictionaries import dictionary


def marker_image(dict_name: str, marker_id: int, px_per_bit: int = 24) -> np.ndarray:
    """(S, S) uint8 printed marker incl. its 1-bit black border, S = (bits + 2)·px_per_bit."""
    d = dictionary(dict_name)
    side = (d.markerSize + 2) * px_per_bit
    return cv2.aruco.generateImageMarker(d, int(marker_id), side, borderBits=1)


def warp_into(dst: np.ndarray, src: np.ndarray, src_corners: np.ndarray, dst_corners: np.ndarray,
              mask: np.ndarray | None = None) -> None:
    """Paint ``src`` into ``dst`` (in place; dst is a caller-owned scratch texture) so that the
    four ``src_corners`` (pixel-edge coordinates, (4, 2)) land on ``dst_corners`` (4, 2).

    The source is low-pass filtered to the destination scale first, so edges keep sub-texel
    positions without aliasing. Only the destination bounding box is touched. ``mask`` (same
    size as src, float 0..1) blends instead of overwriting.
    """
    dst_corners = np.asarray(dst_corners, np.float64)
    H = cv2.getPerspectiveTransform(np.asarray(src_corners, np.float32), dst_corners.astype(np.float32))
    shrink = np.linalg.norm(src_corners[1] - src_corners[0]) / max(  # type: ignore[operator]
        np.linalg.norm(dst_corners[1] - dst_corners[0]), 1e-9)
    s = src.astype(np.float32)
    m = None if mask is None else mask.astype(np.float32)
    if shrink > 1.0:
        sig = 0.5 * shrink
        s = cv2.GaussianBlur(s, (0, 0), sig)  # type: ignore[assignment]  # cv2's stubs
        m = None if m is None else cv2.GaussianBlur(m, (0, 0), sig)  # type: ignore[assignment]  # cv2's stubs
    x0 = max(int(np.floor(dst_corners[:, 0].min())) - 2, 0)
    y0 = max(int(np.floor(dst_corners[:, 1].min())) - 2, 0)
    x1 = min(int(np.ceil(dst_corners[:, 0].max())) + 3, dst.shape[1])
    y1 = min(int(np.ceil(dst_corners[:, 1].max())) + 3, dst.shape[0])
    if x1 <= x0 or y1 <= y0:
        return
    T = np.array([[1, 0, -x0], [0, 1, -y0], [0, 0, 1]], float) @ H
    size = (x1 - x0, y1 - y0)
    warped = cv2.warpPerspective(s, T, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    ones = np.ones(src.shape[:2], np.float32) if m is None else m
    a = cv2.warpPerspective(ones, T, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT,
                            borderValue=0)
    roi = dst[y0:y1, x0:x1]
    if roi.ndim == 3 and warped.ndim == 2:
        warped = warped[..., None]
    if roi.ndim == 3:
        a = a[..., None]
    roi[...] = (roi.astype(np.float32) * (1 - a) + warped * a).astype(dst.dtype)


def pixel_edge_square(side_px: int) -> np.ndarray:
    """(4, 2) pixel-edge corners of a side_px × side_px image, OpenCV order TL, TR, BR, BL."""
    e = side_px - 0.5
    return np.array([[-0.5, -0.5], [e, -0.5], [e, e], [-0.5, e]], np.float64)


def disc_coverage(dist_px: np.ndarray, radius_px: float) -> np.ndarray:
    """Anti-aliased coverage (0..1) of a disc of ``radius_px`` at distance ``dist_px``."""
    return np.clip(radius_px - dist_px + 0.5, 0.0, 1.0)
