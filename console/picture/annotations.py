"""What an experiment drew, for renderers: the picture's ``annotations`` as outlines, discs and texts.

The picture carries the Frame's :class:`~swarmdeck.core.annotations.Annotations` as they are (arena metres,
RGBA, already within the caps). Renderers that draw lines only (the viser scene, Foxglove's line lists) take
:func:`annotation_segments`: every polyline, polygon outline and circle outline as segments, with each
segment's colour and width; filled polygons and circles and the points are :func:`filled_polygons` (circles
as :data:`CIRCLE_SEGMENTS`-gons); texts are :func:`annotation_texts`. Renderers with their own circles
and fills (OpenCV, a 2-D canvas) may draw the primitives directly; browser canvases take
:func:`annotations_json` (the portal's live view; ``static/live.js`` ``drawAnnotations`` draws it).
Vectorised; no drawing library.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.annotations import CIRCLE, POINT, POLYGON, POLYLINE, TEXT, Annotations

#: sides of the polygon a circle is drawn as by renderers without circles
CIRCLE_SEGMENTS = 32


def _unit_circle(k: int) -> NDArray[np.float64]:
    t = np.linspace(0.0, 2.0 * np.pi, k, endpoint=False)
    return np.column_stack((np.cos(t), np.sin(t)))


def annotation_segments(ann: Annotations, circle_segments: int = CIRCLE_SEGMENTS
                        ) -> tuple[NDArray[np.float64], NDArray[np.uint8], NDArray[np.float64]]:
    """Every outline of ``ann`` as segments: ``(S, 2, 2)`` m, their colours ``(S, 4)`` uint8 RGBA and widths
    ``(S,)`` m — polylines (consecutive vertices), polygons not filled (closed) and circles not filled
    (``circle_segments``-gons of their radius)."""
    segs: list[NDArray[np.float64]] = []
    cols: list[NDArray[np.uint8]] = []
    widths: list[NDArray[np.float64]] = []
    if len(ann):
        v, o = ann.vertices, ann.offsets
        counts = np.diff(o)
        prim = np.repeat(np.arange(len(ann)), counts)
        # consecutive vertices of the same primitive: polylines and polygon outlines
        lines = (ann.kinds == POLYLINE) | ((ann.kinds == POLYGON) & ~ann.filled)
        same = (prim[1:] == prim[:-1]) & lines[prim[:-1]]
        if same.any():
            idx = np.flatnonzero(same)
            segs.append(np.stack((v[idx], v[idx + 1]), axis=1))
            p = prim[idx]
            cols.append(ann.colors[p])
            widths.append(ann.sizes[p])
        closing = np.flatnonzero((ann.kinds == POLYGON) & ~ann.filled)
        if len(closing):
            segs.append(np.stack((v[o[closing + 1] - 1], v[o[closing]]), axis=1))
            cols.append(ann.colors[closing])
            widths.append(ann.sizes[closing])
        rings = np.flatnonzero((ann.kinds == CIRCLE) & ~ann.filled)
        if len(rings):
            unit = _unit_circle(circle_segments)
            c = v[o[rings]]
            ring = c[:, None, :] + ann.sizes[rings][:, None, None] * unit[None]  # (R, k, 2)
            segs.append(np.stack((ring, np.roll(ring, -1, axis=1)), axis=2).reshape(-1, 2, 2))
            cols.append(np.repeat(ann.colors[rings], circle_segments, axis=0))
            widths.append(np.full(len(rings) * circle_segments, 0.01))
    if not segs:
        return np.zeros((0, 2, 2)), np.zeros((0, 4), dtype=np.uint8), np.zeros(0)
    return np.concatenate(segs), np.concatenate(cols), np.concatenate(widths)


def filled_polygons(ann: Annotations, circle_segments: int = CIRCLE_SEGMENTS
                    ) -> tuple[list[NDArray[np.float64]], NDArray[np.uint8]]:
    """The filled shapes of ``ann``: filled polygons, filled circles and points (discs of their radius) as
    polygons ``[(V_i, 2)]`` m and their colours ``(F, 4)`` uint8 RGBA, in drawing order."""
    idx = np.flatnonzero(((ann.kinds == POLYGON) & ann.filled) | ((ann.kinds == CIRCLE) & ann.filled)
                         | (ann.kinds == POINT))
    unit = _unit_circle(circle_segments)
    polys = [ann.vertices[ann.offsets[i]:ann.offsets[i + 1]] if ann.kinds[i] == POLYGON
             else ann.vertices[ann.offsets[i]] + ann.sizes[i] * unit for i in idx]
    return polys, ann.colors[idx] if len(idx) else np.zeros((0, 4), dtype=np.uint8)


def annotation_texts(ann: Annotations) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.uint8], list[str]]:
    """The texts of ``ann``: anchors ``(T, 2)`` m (text centred there), heights ``(T,)`` m, colours ``(T, 4)``
    and the strings."""
    idx = np.flatnonzero(ann.kinds == TEXT)
    return (ann.vertices[ann.offsets[idx]] if len(idx) else np.zeros((0, 2)), ann.sizes[idx], ann.colors[idx],
            [ann.texts[i] for i in idx])


def annotations_json(ann: Annotations) -> dict[str, Any]:
    """``ann`` as JSON for a canvas: ``{kinds (P,), offsets (P + 1,), vertices (V, 2) m rounded to 0.1 mm,
    sizes (P,) m, colours (P,) "rgba(r,g,b,a)", filled (P,), texts (P,)}`` — kinds 0 point, 1 polyline,
    2 circle, 3 polygon, 4 text."""
    rgba = [f"rgba({r},{g},{b},{al / 255:.3f})" for r, g, b, al in ann.colors.tolist()]
    return {"kinds": ann.kinds.tolist(), "offsets": ann.offsets.tolist(),
            "vertices": np.round(ann.vertices, 4).tolist(), "sizes": np.round(ann.sizes, 4).tolist(),
            "colours": rgba, "filled": ann.filled.tolist(), "texts": list(ann.texts)}
