"""What every renderer of a Frame agrees on: the rules and sizes of the picture (a frozen dataclass).

Renderer-specific styles extend it (the viser scene's ``SceneStyle`` is a subclass), so
one ``PictureStyle`` decides for all of them which robots count as changed, how active
pairs are coloured, which safety distance is drawn when a Frame has no barrier, and up
to how many robots labels and per-robot glyphs are drawn.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from swarmdeck.core.constants import SAFETY_DISTANCE


@dataclass(frozen=True)
class PictureStyle:
    """The rules of the picture; sizes in m, speeds in m/s.

    Attributes:
        changed_threshold: a robot is "changed" when the barrier moved its command by more than this, m/s
            (the Frame's ``barrier.intervention``; the metrics' ``robots_changed`` counts the same robots).
        h_full: active pairs are red at h ≤ 0 and yellow at h ≥ this barrier value, m².
        safety_distance: D_s drawn (safety rings of radius D_s / 2) when a Frame carries no barrier, m
            (REFERENCE.md §3: 0.17 m).
        heatmap_px_per_m: heat-map sampling, px per m (lowered on large arenas, :meth:`heatmap_px`).
        heatmap_max_px: the heat map keeps under this many pixels.
        arrow_scale: an arrow is the distance its command travels in this time, s.
        label_offset: robot ids sit this far above the robot, m.
        max_labels: robot ids only up to this many robots.
        max_glyphs: per-robot glyphs (arrows, safety rings, trails, sensor rays) only up to this many robots.
        sensors: draw the sensors' layer (ToF rays and end points, LED colours) when a Frame has sensors.
    """

    changed_threshold: float = 1e-3
    h_full: float = 0.1
    safety_distance: float = SAFETY_DISTANCE
    heatmap_px_per_m: float = 50.0
    heatmap_max_px: int = 40_000
    arrow_scale: float = 1.5
    label_offset: float = 0.07
    max_labels: int = 100
    max_glyphs: int = 300
    sensors: bool = True

    def heatmap_px(self, bounds: tuple[float, float, float, float]) -> float:
        """Heat-map px per m on the arena ``bounds`` (x_min, x_max, y_min, y_max) m: ``heatmap_px_per_m``,
        lowered so that the image keeps under ``heatmap_max_px`` pixels."""
        x0, x1, y0, y1 = bounds
        return min(self.heatmap_px_per_m, math.sqrt(self.heatmap_max_px / ((x1 - x0) * (y1 - y0))))
