"""What an experiment drew, in the viser scene: the ``annotations`` layer of :class:`~.scene.ArenaScene`.

The picture's annotations (:mod:`swarmdeck.console.picture.annotations`) as three kinds of node under
``/annotations``: one line-segment node for every outline (polylines, polygons, circles — filled shapes are
drawn as their outlines: viser has no 2-D fill), one point cloud for the points (per-point colour), and text
labels in the scene's units (their height is the text's height, m), at most :data:`MAX_LABELS` of them (a pool
reused from Frame to Frame: a label node is only created when more texts are shown than ever before).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.picture.annotations import annotation_segments, annotation_texts
from swarmdeck.core.annotations import POINT, Annotations

if TYPE_CHECKING:
    import viser

#: texts drawn as viser labels at most (more would swamp the browser with nodes)
MAX_LABELS = 64
_Z = 0.005  # above the floor and the cells, below the robots
_HIDDEN = np.array([[[0.0, 0.0, -5.0], [0.0, 0.0, -5.0]]], dtype=np.float32)


class AnnotationNodes:
    """The ``annotations`` layer's nodes in ``scene`` (module docstring); :attr:`visible` shows or hides all."""

    def __init__(self, scene: viser.SceneApi, root: str = "") -> None:
        self.scene = scene
        self.root = root  # a prefix of the nodes' names (the ArenaScene's root)
        self.lines = scene.add_line_segments(f"{root}/annotations/lines", _HIDDEN, (0, 0, 0), thickness=0.008)
        self.points = scene.add_point_cloud(f"{root}/annotations/points", np.zeros((1, 3), np.float32) - [0, 0, 5],
                                            (0, 0, 0), point_size=0.03, point_shape="circle", precision="float32")
        self.labels: list[viser.LabelHandle] = []
        self._shown_labels = 0
        self._visible = True
        self.drawn = 0
        """primitives drawn by the last :meth:`draw`"""

    @property
    def visible(self) -> bool:
        """Whether the layer is shown."""
        return self._visible

    @visible.setter
    def visible(self, value: bool) -> None:
        self._visible = bool(value)
        self.lines.visible = self.points.visible = self._visible
        for i, label in enumerate(self.labels):
            label.visible = self._visible and i < self._shown_labels

    def draw(self, ann: Annotations) -> None:
        """Show ``ann`` (arena metres) in place of what was shown."""
        segs, cols, _ = annotation_segments(ann)
        if len(segs):
            self.lines.points = np.concatenate((segs, np.full((len(segs), 2, 1), _Z)), axis=2).astype(np.float32)
            self.lines.colors = np.repeat(cols[:, None, :3], 2, axis=1)
        else:
            self.lines.points = _HIDDEN
        pts = np.flatnonzero(ann.kinds == POINT)
        if len(pts):
            xy: NDArray[np.float64] = ann.vertices[ann.offsets[pts]]
            self.points.points = np.column_stack((xy, np.full(len(xy), _Z))).astype(np.float32)
            self.points.colors = ann.colors[pts, :3]
        else:
            self.points.points = np.zeros((1, 3), np.float32) - np.array([0, 0, 5], np.float32)
        anchors, heights, _, texts = annotation_texts(ann)
        shown = min(len(texts), MAX_LABELS)
        while len(self.labels) < shown:
            self.labels.append(self.scene.add_label(f"{self.root}/annotations/text{len(self.labels)}", "", font_size_mode="scene",
                                                    anchor="center-center", visible=False))
        for i, label in enumerate(self.labels):
            if i < shown:
                label.text = texts[i]
                label.position = (float(anchors[i, 0]), float(anchors[i, 1]), _Z)
                label.font_scene_height = float(heights[i])
            label.visible = self._visible and i < shown
        self._shown_labels = shown
        self.drawn = len(ann)
