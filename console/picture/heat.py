"""The density heat map: φ(q, t) of a Frame as an RGB(A) image over the arena (REFERENCE.md §5)."""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.picture.colours import LUT
from swarmdeck.core.bounds import Bounds

if TYPE_CHECKING:
    from swarmdeck.coverage.density import GaussianMixture


def heatmap(density: GaussianMixture, bounds: Bounds, px_per_m: float,
            alpha: tuple[float, float] | None = None) -> NDArray[np.uint8]:
    """RGB image (H, W, 3) of φ over the arena, row 0 at y_max, colour-mapped by φ / max φ (:data:`LUT`).

    With ``alpha = (lo, hi)`` (opacities in [0, 1]): RGBA (H, W, 4) with opacity rising linearly
    from ``lo`` at φ = 0 to ``hi`` at max φ, to lay over the camera picture.
    """
    x0, x1, y0, y1 = bounds
    w = max(2, int(round((x1 - x0) * px_per_m)))
    h = max(2, int(round((y1 - y0) * px_per_m)))
    xs = x0 + (np.arange(w) + 0.5) * (x1 - x0) / w
    ys = y1 - (np.arange(h) + 0.5) * (y1 - y0) / h
    gx, gy = np.meshgrid(xs, ys)
    phi = density.evaluate(np.stack((gx, gy), axis=-1))
    top = float(phi.max())
    idx = np.zeros(phi.shape, dtype=np.intp) if top <= 0 else np.clip(phi / top * 255.0, 0, 255).astype(np.intp)
    if alpha is None:
        return LUT[idx]
    a = np.round(255.0 * (alpha[0] + (alpha[1] - alpha[0]) * idx / 255.0)).astype(np.uint8)
    return np.concatenate((LUT[idx], a[:, :, None]), axis=2)
