"""Geometry of square ArUco tags in the arena plane (pure functions on numpy arrays).

Corner order is OpenCV's: top-left, top-right, bottom-right, bottom-left of the printed tag.
Seen from above the printed tag is the same picture in the image and in the arena, so the order
is visually clockwise in both; numerically the shoelace area is positive in image coordinates
(y down) and negative in arena coordinates (y up) — the sign flip REFERENCE.md §7 refers to.

Heading convention (the Robotarium's, robotarium.md §4.4): a tag is mounted with its printed
+x edge (top-left → top-right) along the robot's forward axis, so the heading is the direction
of ``0.5·(c1 + c2 − c0 − c3)``. A reference marker at heading 0 is printed upright in a
top-down view (its "up" along arena +y).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def marker_corners(centres: np.ndarray, headings: np.ndarray, size: float | np.ndarray) -> np.ndarray:
    """Arena corners of square tags.

    centres (N, 2) m, headings (N,) rad (direction of the tag's +x edge), size scalar or (N,)
    side length in m. Returns (N, 4, 2) corners in OpenCV order (TL, TR, BR, BL).
    """
    c = np.asarray(centres, dtype=float).reshape(-1, 2)
    th = np.asarray(headings, dtype=float).reshape(-1)
    half = 0.5 * np.broadcast_to(np.asarray(size, dtype=float), th.shape)
    r = np.stack([np.cos(th), np.sin(th)], axis=1) * half[:, None]        # tag +x (right)
    u = np.stack([-np.sin(th), np.cos(th)], axis=1) * half[:, None]       # tag up
    return np.stack([c - r + u, c + r + u, c + r - u, c - r - u], axis=1)


def poses_from_corners(corners: np.ndarray) -> np.ndarray:
    """Poses from arena corners (N, 4, 2) in OpenCV order → (N, 3) ``[x, y, θ]``.

    Position: mean of the four corners (the centre of the square). Heading: angle of
    ``0.5·(c1 + c2 − c0 − c3)``, the tag's +x direction, in (−π, π].
    """
    c = np.asarray(corners, dtype=float).reshape(-1, 4, 2)
    centre = c.mean(axis=1)
    fwd = 0.5 * (c[:, 1] + c[:, 2] - c[:, 0] - c[:, 3])
    return np.column_stack([centre, np.arctan2(fwd[:, 1], fwd[:, 0])])


@dataclass(frozen=True)
class ReferenceMarker:
    """A fixed tag at a surveyed arena position: id, centre (x, y) m, side m, heading rad."""

    id: int
    x: float
    y: float
    size: float = 0.10
    heading: float = 0.0

    def corners(self) -> np.ndarray:
        """(4, 2) arena corners in OpenCV order."""
        return marker_corners(np.array([[self.x, self.y]]), np.array([self.heading]), self.size)[0]


# Four references just outside the default 3.2 m × 2.0 m arena, so robots never cover them;
# ids 46–49 are the top of DICT_4X4_50 (robots use 0–45), as the Robotarium keeps its
# references at the top of its dictionary (ids 47–50 of 4X4_100).
DEFAULT_REFERENCES: tuple[ReferenceMarker, ...] = (
    ReferenceMarker(46, -1.70, -1.10),
    ReferenceMarker(47, 1.70, -1.10),
    ReferenceMarker(48, 1.70, 1.10),
    ReferenceMarker(49, -1.70, 1.10),
)


def reference_corners(references: tuple[ReferenceMarker, ...]) -> tuple[np.ndarray, np.ndarray]:
    """ids (R,) and arena corners (R, 4, 2) of a reference layout."""
    ids = np.array([r.id for r in references], dtype=int)
    if len(references) == 0:
        return ids, np.zeros((0, 4, 2))
    return ids, np.stack([r.corners() for r in references])
