"""What an experiment drew, rasterised with OpenCV: the video's annotations (``export_video``).

:func:`draw_annotations` draws the picture's :class:`~swarmdeck.core.annotations.Annotations` onto an RGB
image through any arena → pixel map (the video's :class:`~.export_video.VideoLayout`; a homography would do):
filled polygons and circles and the points filled, polylines and outlines ``sizes`` m wide, texts centred on
their anchor, ``sizes`` m tall (OpenCV's Hershey font). Colours are the annotations' RGBA; alpha below 255
is blended over what is under the shape (quantised to eighths). One OpenCV call per primitive: the caps
(:class:`~swarmdeck.core.annotations.AnnotationLimits`) bound the cost.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.annotations import CIRCLE, POINT, POLYGON, POLYLINE, TEXT, Annotations

_SHIFT = 4
_ONE = 1 << _SHIFT
_ALPHA_LEVELS = 8  # translucent colours are blended at alpha quantised to eighths (one overlay per level)
_HERSHEY_HEIGHT = 22.0  # px of an upper-case Hershey simplex glyph at fontScale 1


def draw_annotations(img: NDArray[np.uint8], ann: Annotations, to_px: Callable[[NDArray[np.float64]], NDArray[np.float64]],
                     px_per_m: float) -> None:
    """Draw ``ann`` into ``img`` (H, W, 3) uint8 RGB in place; ``to_px`` maps (…, 2) m to (…, 2) pixels
    (column, row), ``px_per_m`` scales sizes."""
    if not len(ann):
        return
    import cv2

    aa = cv2.LINE_AA
    px = to_px(ann.vertices)
    fixed = np.round(px * _ONE).astype(np.int32)

    def one(target: NDArray[np.uint8], i: int) -> None:
        colour: Any = tuple(int(c) for c in ann.colors[i, :3])
        kind, a, b = int(ann.kinds[i]), int(ann.offsets[i]), int(ann.offsets[i + 1])
        size_px = float(ann.sizes[i]) * px_per_m
        if kind in (POINT, CIRCLE):
            centre = (int(fixed[a, 0]), int(fixed[a, 1]))
            radius = max(1, int(round(size_px * _ONE)))
            thickness = -1 if kind == POINT or ann.filled[i] else max(1, int(round(0.01 * px_per_m)))
            cv2.circle(target, centre, radius, colour, thickness, aa, _SHIFT)
        elif kind == POLYGON and ann.filled[i]:
            cv2.fillPoly(target, [fixed[a:b]], colour, aa, _SHIFT)
        elif kind in (POLYLINE, POLYGON):
            cv2.polylines(target, [fixed[a:b]], kind == POLYGON, colour, max(1, int(round(size_px))), aa, _SHIFT)
        elif kind == TEXT:
            scale = max(0.2, size_px / _HERSHEY_HEIGHT)
            (tw, th), _ = cv2.getTextSize(ann.texts[i], cv2.FONT_HERSHEY_SIMPLEX, scale, 1)
            org = (int(px[a, 0] - tw / 2), int(px[a, 1] + th / 2))
            cv2.putText(target, ann.texts[i], org, cv2.FONT_HERSHEY_SIMPLEX, scale, colour,
                        max(1, int(round(scale * 1.5))), aa)

    # opaque shapes straight onto the image; translucent ones onto one overlay per alpha level (of 8), blended once
    level = np.round(ann.colors[:, 3].astype(float) / 255.0 * _ALPHA_LEVELS).astype(int)
    for i in np.flatnonzero(level == _ALPHA_LEVELS):
        one(img, int(i))
    for lv in range(1, _ALPHA_LEVELS):
        sel = np.flatnonzero(level == lv)
        if not len(sel):
            continue
        overlay = img.copy()
        for i in sel:
            one(overlay, int(i))
        alpha = lv / _ALPHA_LEVELS
        cv2.addWeighted(overlay, alpha, img, 1.0 - alpha, 0.0, dst=img)
