"""One renderer-neutral picture of a Frame: what to draw, as numpy arrays (no drawing library here).

:func:`picture_of` turns a :class:`~swarmdeck.console.runtime.frame.Frame` and a
:class:`~swarmdeck.console.picture.style.PictureStyle` into a :class:`Picture`; the
small functions it is built from (:func:`robot_colors`, :func:`changed_mask`,
:func:`active_pairs`, :func:`safety_distance`, :func:`cell_shades`) are the only place
their rules live. The backends — the viser scene (``console.web.scene``, live, playback
and the HTML export), the MP4 video (``console.recording.export_video``), the Foxglove
channels (``console.recording.foxglove``) and the portal's live view
(``console.portal.live`` + ``static/live.js``) — only turn these arrays into their
primitives, so they show the same colours, the same active pairs and the same changed
robots by construction. Units: m, rad, m/s; N robots, K active pairs, E Voronoi edges.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, TypeVar

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.picture.colours import (
    CHANGED,
    PAUSED,
    ROBOT,
    STOPPED,
    UNSEEN,
    VIRTUAL_PALE,
    pair_colors,
)
from swarmdeck.console.picture.heat import heatmap
from swarmdeck.console.picture.network import NetworkLayer, network_layer
from swarmdeck.console.picture.sensing import SensorLayer, sensor_layer
from swarmdeck.console.picture.style import PictureStyle
from swarmdeck.console.runtime.behaviours import goals_of_frame
from swarmdeck.console.runtime.frame import Frame, filled
from swarmdeck.core.annotations import EMPTY, Annotations, sanitize
from swarmdeck.core.bounds import Bounds

if TYPE_CHECKING:
    from swarmdeck.coverage.density import GaussianMixture

DEFAULT_STYLE = PictureStyle()
_Scalar = TypeVar("_Scalar", bound=np.generic)


def changed_mask(frame: Frame, style: PictureStyle = DEFAULT_STYLE) -> NDArray[np.bool_]:
    """(N,) True for the robots whose command the barrier changed by more than ``style.changed_threshold``
    m/s (all False when the Frame has no barrier or its intervention does not cover the N robots)."""
    b = frame.barrier
    if b is None or len(b.intervention) != frame.n:
        return np.zeros(frame.n, dtype=bool)
    return np.asarray(b.intervention > style.changed_threshold)


def robot_colors(frame: Frame, style: PictureStyle = DEFAULT_STYLE) -> NDArray[np.uint8]:
    """(N, 3) colours by state: stopped red, paused slate, unseen grey, changed by the barrier orange, else
    blue; virtual robots the same blended :data:`~.colours.VIRTUAL_PALE` toward white."""
    cols = np.tile(ROBOT, (frame.n, 1))
    cols[changed_mask(frame, style)] = CHANGED
    if frame.run_state == "estop":
        cols[:] = STOPPED
    elif frame.run_state == "paused":
        cols[:] = PAUSED
    cols[~filled(frame.seen)] = UNSEEN
    virtual = filled(frame.is_virtual)
    if virtual.any():
        cols[virtual] = np.round(cols[virtual] * (1.0 - VIRTUAL_PALE) + 255.0 * VIRTUAL_PALE).astype(np.uint8)
    return cols


def active_pairs(frame: Frame) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """The barrier's active pairs ``(K, 2)`` (indices into the Frame's robots) and their barrier values h
    ``(K,)`` m². None at all when the Frame has no barrier, or when a pair names a robot the Frame does not
    have (a Frame assembled from mismatched parts draws no pair rather than a wrong one)."""
    b = frame.barrier
    if b is None or not len(b.active_pairs) or int(b.active_pairs.max()) >= frame.n:
        return np.empty((0, 2), dtype=np.int64), np.empty(0)
    return np.asarray(b.active_pairs, dtype=np.int64), np.asarray(b.active_h, dtype=float)


def safety_distance(frame: Frame, style: PictureStyle = DEFAULT_STYLE) -> float:
    """D_s of the Frame's barrier, m, or ``style.safety_distance`` when it has none."""
    return frame.barrier.safety_distance if frame.barrier is not None else style.safety_distance


def cell_shades(masses: NDArray[np.float64]) -> NDArray[np.float64]:
    """(C, 3) RGB (float, 0–255) fill of the Voronoi cells by their mass: pale blue (empty) → blue (heaviest)."""
    m = masses / max(float(masses.max()), 1e-12)
    return np.array([200, 220, 255])[None] * (1 - m[:, None]) + np.array([60, 110, 220])[None] * m[:, None]


def _frozen(a: NDArray[_Scalar]) -> NDArray[_Scalar]:
    a = np.asarray(a)
    if a.flags.writeable:
        a = a.copy() if a.base is not None else a
        a.flags.writeable = False
    return a


@dataclass(frozen=True)
class Picture:
    """What to draw of one Frame (module docstring). Arrays are read-only.

    Attributes:
        bounds: the arena (x_min, x_max, y_min, y_max), m.
        ids, poses, points: (N,) robot ids, (N, 3) [x, y, θ], (N, 2) look-ahead points.
        colors: (N, 3) uint8 robot colours by state (:func:`robot_colors`).
        changed: (N,) the robots whose command the barrier changed (:func:`changed_mask`).
        virtual: (N,) the virtual robots (drawn pale, in a dashed violet ring).
        pairs, pair_h, pair_colors: (K, 2) active barrier pairs (between look-ahead points), (K,) their h,
            m², (K, 3) uint8 their colours (red at h ≤ 0 → yellow).
        ring_radius: radius of the safety ring round every look-ahead point, D_s / 2, m.
        nominal_tips, safe_tips: (N, 2) tips of the nominal and safe command arrows starting at the
            look-ahead points (``style.arrow_scale`` s of travel), m.
        label_xy: (N, 2) where the robots' ids go, m.
        labelled: ids are drawn (N ≤ ``style.max_labels``).
        glyphs: per-robot glyphs — arrows, safety rings, trails — are drawn (N ≤ ``style.max_glyphs``).
        edges, centroids: (E, 2, 2) Voronoi edges and (C, 2) centroids, empty without coverage.
        cell_vertices, cell_offsets, cell_shades: the filled Voronoi cells — cell k is the polygon
            ``cell_vertices[cell_offsets[k]:cell_offsets[k + 1]]`` (m) shaded ``cell_shades[k]`` (RGB float
            0–255 by mass, :func:`cell_shades`); no cell without coverage.
        contacts: (M, 2) touch contacts. goals: (G, 2) goals of the goto behaviour (else empty).
        density: φ(·, t) for :meth:`heat_map`, or None.
        run_state, behaviour, events, alerts: the Frame's, for banners and logs.
        sensors: the sensors' layer (:class:`~.sensing.SensorLayer`: ToF rays, LEDs), None without sensors.
        obstacles: (S, 2, 2) line-segment obstacles on the floor, m (``Frame.obstacles``; empty without),
            drawn in :data:`~.colours.OBSTACLE`, ``PictureStyle``-independent (always drawn).
        network: the communication graph (:class:`~.network.NetworkLayer`), None when the Frame has none.
        annotations: what the experiment drew (arena metres, RGBA; :mod:`.annotations` turns it into
            segments, filled polygons and texts), empty when it drew nothing.
    """

    bounds: Bounds
    ids: NDArray[np.int64]
    poses: NDArray[np.float64]
    points: NDArray[np.float64]
    colors: NDArray[np.uint8]
    changed: NDArray[np.bool_]
    virtual: NDArray[np.bool_]
    pairs: NDArray[np.int64]
    pair_h: NDArray[np.float64]
    pair_colors: NDArray[np.uint8]
    ring_radius: float
    nominal_tips: NDArray[np.float64]
    safe_tips: NDArray[np.float64]
    label_xy: NDArray[np.float64]
    labelled: bool
    glyphs: bool
    edges: NDArray[np.float64]
    centroids: NDArray[np.float64]
    cell_vertices: NDArray[np.float64]
    cell_offsets: NDArray[np.int64]
    cell_shades: NDArray[np.float64]
    contacts: NDArray[np.float64]
    goals: NDArray[np.float64]
    density: GaussianMixture | None
    run_state: str
    behaviour: str
    events: tuple[str, ...]
    alerts: tuple[str, ...]
    sensors: SensorLayer | None = None
    obstacles: NDArray[np.float64] = field(default_factory=lambda: _frozen(np.zeros((0, 2, 2))))
    network: NetworkLayer | None = None
    annotations: Annotations = EMPTY

    @property
    def n(self) -> int:
        """Number of robots N."""
        return int(self.poses.shape[0])

    def heat_map(self, px_per_m: float, alpha: tuple[float, float] | None = None) -> NDArray[np.uint8] | None:
        """The density heat map at ``px_per_m`` (:func:`~.heat.heatmap`; RGBA with ``alpha``), None without a density."""
        return None if self.density is None else heatmap(self.density, self.bounds, px_per_m, alpha)


def picture_of(frame: Frame, style: PictureStyle = DEFAULT_STYLE) -> Picture:
    """The :class:`Picture` of ``frame`` drawn with ``style``. Vectorised over robots; no drawing library."""
    n = frame.n
    pts = frame.points
    pairs, h = active_pairs(frame)
    cov = frame.coverage
    goals = goals_of_frame(frame.params, n, frame.bounds) if frame.behaviour == "goto" else np.zeros((0, 2))
    return Picture(
        bounds=frame.bounds, ids=frame.ids, poses=frame.poses, points=_frozen(pts),
        colors=_frozen(robot_colors(frame, style)), changed=_frozen(changed_mask(frame, style)),
        virtual=filled(frame.is_virtual), pairs=_frozen(pairs), pair_h=_frozen(h), pair_colors=_frozen(pair_colors(h, style.h_full)),
        ring_radius=0.5 * safety_distance(frame, style),
        nominal_tips=_frozen(pts + style.arrow_scale * frame.nominal),
        safe_tips=_frozen(pts + style.arrow_scale * frame.safe),
        label_xy=_frozen(frame.poses[:, :2] + np.array([0.0, style.label_offset])),
        labelled=n <= style.max_labels, glyphs=n <= style.max_glyphs,
        edges=cov.edges if cov is not None else np.zeros((0, 2, 2)),
        centroids=cov.centroids if cov is not None else np.zeros((0, 2)),
        cell_vertices=cov.cell_vertices if cov is not None else np.zeros((0, 2)),
        cell_offsets=cov.cell_offsets if cov is not None else np.zeros(1, dtype=np.int64),
        cell_shades=_frozen(cell_shades(cov.masses)) if cov is not None and len(cov.masses) else np.zeros((0, 3)),
        contacts=frame.contacts.positions, goals=_frozen(np.asarray(goals, dtype=float)),
        density=frame.density, run_state=frame.run_state, behaviour=frame.behaviour,
        events=frame.events, alerts=frame.alerts, sensors=sensor_layer(frame, style),
        obstacles=frame.obstacles.segments if frame.obstacles is not None else _frozen(np.zeros((0, 2, 2))),
        network=network_layer(frame, style),
        annotations=drawn(frame),
    )


def drawn(frame: Frame) -> Annotations:
    """What the Frame's experiment drew, within the caps (``swarmdeck.core.annotations.sanitize`` with the default
    limits on the Frame's bounds: a recording from elsewhere cannot make a renderer draw a million primitives);
    the Frame's own annotations when they are within them, EMPTY when it has none."""
    if frame.annotations is None or not len(frame.annotations):
        return EMPTY
    return sanitize(frame.annotations, frame.bounds)[0]
