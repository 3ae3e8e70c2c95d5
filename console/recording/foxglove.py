"""Foxglove-native channels of a Frame: what Foxglove's 3D, Image, Plot and Log panels draw (REFERENCE.md §13).

:class:`FoxgloveEncoder` turns each :class:`~swarmdeck.console.runtime.frame.Frame`
into messages of Foxglove's well-known schemas, built and serialised by the
official ``foxglove-sdk`` (``foxglove.messages``; the schemas are the SDK's own
``get_schema()`` protobuf descriptors, never copied text). The recorder writes
them beside its own ``/swarmdeck/frame`` channel on its background writer
thread; :mod:`swarmdeck.console.web.foxglove_live` serves the same messages over
the Foxglove WebSocket protocol. Topics (:data:`TOPICS`):

========================  ==========================  ==============================================
topic                     schema                      content (frame ``arena``: x right, y up, m)
========================  ==========================  ==============================================
``/foxglove/robots``      ``foxglove.SceneUpdate``    entity ``arena`` (the boundary, a line loop) and
                                                      entity ``robots``: one disc (cylinder, ⌀ 0.11 m) and
                                                      one heading arrow per robot, coloured by state like
                                                      the console (blue; orange when the barrier changed
                                                      the command; red e-stop; slate paused; grey unseen),
                                                      ids as text
``/foxglove/cells``       ``foxglove.SceneUpdate``    Voronoi edges (a line list) of the coverage state
``/foxglove/barrier``     ``foxglove.SceneUpdate``    active barrier pairs between look-ahead points, a
                                                      line list coloured by h (red h ≤ 0 → yellow)
``/foxglove/network``     ``foxglove.SceneUpdate``    the robots' communication links (a line list, idle →
                                                      busy by messages/s; only in decentralised runs,
                                                      :data:`NETWORK_TOPICS`)
``/foxglove/contacts``    ``foxglove.SceneUpdate``    touch contacts as spheres
``/foxglove/annotations`` ``foxglove.SceneUpdate``    what the experiment drew (entity ``annotations``):
                                                      outlines as a line list, filled shapes as
                                                      triangles, points as spheres, texts as texts,
                                                      in their RGBA; with the cells' cadence
``/foxglove/poses``       ``foxglove.PosesInFrame``   robot poses [x, y, θ] in ``arena``
``/foxglove/density``     ``foxglove.Grid``           φ(q, t) on a 0.1 m grid (float32 field ``phi``; the
                                                      layout interpolates), every ``density_period`` s
``/foxglove/camera``      ``foxglove.CompressedImage``  the rectified overhead picture (JPEG), every
                                                      ``camera_period`` s when a camera runs
``/foxglove/tf``          ``foxglove.FrameTransforms``  ``world → arena`` (identity) and ``arena → camera``
                                                      (overhead, looking down)
``/foxglove/log``         ``foxglove.Log``            frame events (info), alerts when they appear
``/foxglove/sensors``     ``foxglove.SceneUpdate``    the sensors' layer: ToF rays and end points, lit LEDs (only for
                                                      Frames with sensors; :data:`OPTIONAL_TOPICS`)
                                                      (warning) and clear (info), operator actions
``/swarmdeck/metrics``    JSON (``swarmdeck.Metrics``)  plottable scalars: min distance, wall clearance,
                                                      H, mean ‖p − c‖, tick time, solver time, …
========================  ==========================  ==============================================

The SDK builds messages from Python objects, so building the robots' scene is a
list comprehension over robots (≈ 20 µs per robot; measured in
``bench/bench_foxglove.py``): it runs on the recorder's writer thread or the
live bridge's thread, never on the control loop's.

Thinning at large N (:class:`FoxgloveConfig`): the per-robot channels (``/foxglove/robots``,
``/foxglove/poses``, ``/foxglove/cells``, ``/foxglove/barrier``) carry at most ``robot_rate``
robots per second of recorded time: with N robots they are written every ``N / robot_rate`` s
(:meth:`FoxgloveConfig.scene_period`; by default 10 a second at N = 100, 1 per second at
N = 1000), and the id labels only up to ``max_labels`` robots (as in the console's scene). The
other channels — transforms, contacts, metrics, log, density, camera — keep their rates.
``/swarmdeck/frame`` always has every frame (the full state; Foxglove plays it as raw messages).

Packed (the default since issue 27; ``FoxgloveConfig.per_entity()``, ``--foxglove-entities`` or
``[recording] packed = false`` give the per-robot form): the robots are one
``foxglove.PointCloud`` on ``/foxglove/robot_points`` (:data:`PACKED_TOPICS`; x, y, z, yaw float32 and
rgba uint8, :data:`POINT_STRIDE` = 20 bytes a robot) instead of their primitives on ``/foxglove/robots``
(which keeps the boundary) and ``/foxglove/poses`` (left out); ``lines_period`` thins the cells and
barrier scenes, every second by default (bench/RESULTS.md, "recording size": ≈ 4× smaller at N = 100).
"""
from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.picture.annotations import annotation_segments, annotation_texts, filled_polygons
from swarmdeck.console.picture.colours import (
    BOUNDARY,
    CONTACT,
    HEADING,
    LABEL,
    LINK_IDLE,
    OBSTACLE,
    PAIR,
    SENSOR_HIT,
    SENSOR_RAY,
    VORONOI,
    pair_colors,
)
from swarmdeck.console.picture.network import network_layer
from swarmdeck.console.picture.picture import active_pairs, changed_mask, drawn, robot_colors
from swarmdeck.console.picture.sensing import sensor_layer
from swarmdeck.console.picture.style import PictureStyle
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.core.annotations import POINT, Annotations
from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.constants import ROBOT_RADIUS

TOPIC_ROBOTS = "/foxglove/robots"
TOPIC_CELLS = "/foxglove/cells"
TOPIC_BARRIER = "/foxglove/barrier"
TOPIC_CONTACTS = "/foxglove/contacts"
TOPIC_POSES = "/foxglove/poses"
TOPIC_DENSITY = "/foxglove/density"
TOPIC_CAMERA = "/foxglove/camera"
TOPIC_TF = "/foxglove/tf"
TOPIC_LOG = "/foxglove/log"
TOPIC_METRICS = "/swarmdeck/metrics"
TOPIC_ANNOTATIONS = "/foxglove/annotations"

ARENA_FRAME = "arena"
WORLD_FRAME = "world"
CAMERA_FRAME = "camera"

#: topic -> Foxglove schema (message class name in ``foxglove.messages``; None: the JSON metrics schema)
TOPICS: dict[str, str | None] = {
    TOPIC_ROBOTS: "SceneUpdate", TOPIC_CELLS: "SceneUpdate", TOPIC_BARRIER: "SceneUpdate",
    TOPIC_CONTACTS: "SceneUpdate", TOPIC_POSES: "PosesInFrame", TOPIC_DENSITY: "Grid",
    TOPIC_CAMERA: "CompressedImage", TOPIC_TF: "FrameTransforms", TOPIC_LOG: "Log", TOPIC_METRICS: None,
    TOPIC_ANNOTATIONS: "SceneUpdate",
}

TOPIC_ROBOT_POINTS = "/foxglove/robot_points"

TOPIC_NETWORK = "/foxglove/network"
#: Channels declared always and written only when a Frame has what they show (a decentralised run's links).
NETWORK_TOPICS: dict[str, str | None] = {TOPIC_NETWORK: "SceneUpdate"}

#: Channels written only with ``FoxgloveConfig(packed=True)`` (topic -> schema, as :data:`TOPICS`).
PACKED_TOPICS: dict[str, str | None] = {TOPIC_ROBOT_POINTS: "PointCloud"}

TOPIC_SENSORS = "/foxglove/sensors"

#: Channels declared always and written only for Frames that carry what they show (topic -> schema): the sensors'
#: layer (ToF rays as a line list, their end points as spheres, lit LEDs as discs; issue 28.1).
OPTIONAL_TOPICS: dict[str, str | None] = {TOPIC_SENSORS: "SceneUpdate"}

#: The packed robots' point layout: x, y, z, yaw float32 (m, m, m, rad) then r, g, b, a uint8 (20 bytes a robot).
POINT_STRIDE = 20

#: The plottable fields of ``/swarmdeck/metrics`` (units in the names); null when not defined this tick.
METRIC_FIELDS: dict[str, str] = {
    "t": "recording clock, s",
    "tick": "tick index",
    "min_distance_m": "smallest distance between look-ahead points, m",
    "safety_distance_m": "barrier safety distance D_s, m",
    "min_wall_clearance_m": "smallest clearance to the arena walls, m",
    "n_active": "active barrier constraints",
    "robots_changed": "robots whose command the filter changed by more than 1 mm/s",
    "max_intervention_mps": "largest change the filter made to a command, m/s",
    "solve_time_ms": "barrier QP solve time, ms",
    "cost_H": "locational coverage cost H",
    "mean_centroid_distance_m": "mean distance robot to cell centroid, m",
    "tick_time_ms": "control-loop work per tick, ms",
}

METRICS_SCHEMA: dict[str, Any] = {
    "$schema": "https://json-schema.org/draft/2020-12/schema",
    "title": "swarmdeck.Metrics",
    "description": "Plottable per-tick scalars of the swarmdeck console (null when not defined this tick).",
    "type": "object",
    "required": list(METRIC_FIELDS),
    "properties": {k: {"type": ["number", "null"], "description": d} for k, d in METRIC_FIELDS.items()},
}


@dataclass(frozen=True)
class FoxgloveConfig:
    """What the Foxglove channels carry.

    density_period / camera_period: s of recorded time between density grids / camera pictures
    (0: every frame). density_cell: grid cell size, m. camera_quality: JPEG quality 1–100.
    camera_height: height of the ``camera`` frame above the arena centre, m. labels: draw robot ids.
    robot_rate: robots per second of recorded time the per-robot scene channels may carry (robots,
        poses, cells, barrier): with N robots they are written every N / robot_rate s (0: every
        frame). The default (1000) writes 30 scenes a second up to 33 robots, 10 at N = 100 and 1 at
        N = 1000 (bench/RESULTS.md, "recording size"); 3000 was the default before the packed form.
    max_labels: id labels only up to this many robots (default: the picture's ``PictureStyle.max_labels``, 100).
    packed: (default) the robots as one packed ``foxglove.PointCloud`` on ``/foxglove/robot_points``
        (:data:`POINT_STRIDE` = 20 bytes a robot: x, y, z, yaw float32, rgba uint8) instead of a
        cylinder, an arrow and a label per robot; ``/foxglove/robots`` then carries the arena
        boundary only and ``/foxglove/poses`` is left out (the heading is the cloud's ``yaw``).
        False: one entity per robot (:meth:`per_entity`; ``--foxglove-entities``, ``[recording] packed = false``).
    lines_period: s of recorded time between the Voronoi-edge and barrier-pair scenes (0: with the
        robots' scenes; default 1).
    """

    density_period: float = 0.25
    density_cell: float = 0.1
    camera_period: float = 0.5
    camera_quality: int = 75
    camera_height: float = 2.5
    labels: bool = True
    robot_rate: float = 1000.0
    max_labels: int = PictureStyle.max_labels
    packed: bool = True
    lines_period: float = 1.0

    @classmethod
    def per_entity(cls, **changes: Any) -> FoxgloveConfig:
        """The form before packing was the default: a cylinder, an arrow and a label per robot on
        ``/foxglove/robots`` and its pose on ``/foxglove/poses``, every frame up to 100 robots at 30 Hz
        (robot_rate 3000), the lines with the robots' scenes; ``changes`` override any field."""
        return cls(**{"packed": False, "robot_rate": 3000.0, "lines_period": 0.0, **changes})

    def scene_period(self, n: int) -> float:
        """s of recorded time between the per-robot scene messages of N robots (0: every frame)."""
        return n / self.robot_rate if self.robot_rate > 0 else 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.packed, bool):
            raise ValueError(f"packed must be true or false, got {self.packed!r}")
        for name in ("density_period", "camera_period", "robot_rate", "lines_period"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise ValueError(f"{name} must be a finite number >= 0, got {v!r}")
        for name in ("density_cell", "camera_height"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a finite number > 0 m, got {v!r}")
        if isinstance(self.max_labels, bool) or not isinstance(self.max_labels, int) or self.max_labels < 0:
            raise ValueError(f"max_labels must be an int >= 0, got {self.max_labels!r}")
        if not (isinstance(self.camera_quality, int) and 1 <= self.camera_quality <= 100):
            raise ValueError(f"camera_quality must be an int in [1, 100], got {self.camera_quality!r}")


@dataclass(frozen=True)
class ChannelSpec:
    """One channel as MCAP and the WebSocket protocol declare it."""

    topic: str
    schema_name: str
    schema_encoding: str
    schema_data: bytes
    message_encoding: str


def channel_specs(packed: bool = False) -> list[ChannelSpec]:
    """The channels of :data:`TOPICS` (and :data:`PACKED_TOPICS` with ``packed``), with the SDK's schemas
    (protobuf descriptors) and the metrics JSON Schema."""
    import foxglove.messages as fm

    from swarmdeck.console.recording.recorder import encode_json

    out = []
    for topic, cls in {**TOPICS, **OPTIONAL_TOPICS, **NETWORK_TOPICS, **(PACKED_TOPICS if packed else {})}.items():
        if cls is None:
            out.append(ChannelSpec(topic, METRICS_SCHEMA["title"], "jsonschema", encode_json(METRICS_SCHEMA), "json"))
        else:
            s = getattr(fm, cls).get_schema()
            out.append(ChannelSpec(topic, s.name, s.encoding, bytes(s.data), s.encoding))
    return out


def _num(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None


def _varint(buf: bytes, p: int) -> tuple[int, int]:
    """(value, next position) of the protobuf varint at ``p``; ValueError when it runs past the end."""
    value = shift = 0
    while True:
        if p >= len(buf) or shift > 63:
            raise ValueError("truncated varint")
        b = buf[p]
        p += 1
        value |= (b & 0x7F) << shift
        shift += 7
        if not b & 0x80:
            return value, p


def decode_compressed_image(data: bytes) -> tuple[str, bytes]:
    """(format, image bytes) of a ``foxglove.CompressedImage`` message as :meth:`FoxgloveEncoder.camera`
    writes it (protobuf fields 2 ``data``, 3 ``format``; the SDK encodes but does not decode).
    ValueError when the message is malformed."""
    p, fmt, image = 0, "", b""
    while p < len(data):
        key, p = _varint(data, p)
        field_no, wire = key >> 3, key & 7
        if wire == 0:
            _, p = _varint(data, p)
        elif wire == 2:
            n, p = _varint(data, p)
            if p + n > len(data):
                raise ValueError("field runs past the end of the message")
            if field_no == 2:
                image = data[p:p + n]
            elif field_no == 3:
                fmt = data[p:p + n].decode("utf-8", "replace")
            p += n
        elif wire in (1, 5):
            p += 8 if wire == 1 else 4
        else:
            raise ValueError(f"unsupported protobuf wire type {wire}")
    if p != len(data):
        raise ValueError("field runs past the end of the message")
    return fmt, image


class FoxgloveEncoder:
    """Frames → ``(topic, log_time_ns, bytes)`` messages of :data:`TOPICS`. Not thread-safe: one per writer.

    Args:
        bounds: the arena rectangle (x_min, x_max, y_min, y_max), m.
        robot_radius: disc radius, m.
        config: :class:`FoxgloveConfig`.
        image_provider: ``image_ref -> (RGB image (H, W, 3) row 0 at y_max, bounds) | None`` (the
            camera source's ``image``), or None when no camera runs.
        picture: the picture's rules (changed threshold, pair colours) shared with every other renderer.
    """

    def __init__(self, bounds: Bounds = DEFAULT_BOUNDS,
                 robot_radius: float = ROBOT_RADIUS, config: FoxgloveConfig | None = None,
                 image_provider: Callable[[str], Any] | None = None, picture: PictureStyle | None = None) -> None:
        import foxglove.messages as fm

        self.fm = fm
        self.config = config or FoxgloveConfig()
        self.picture = picture or PictureStyle()
        self.bounds = Bounds(*(float(b) for b in bounds))
        self.radius = float(robot_radius)
        self.image_provider = image_provider
        self._alerts: frozenset[str] = frozenset()
        self._next_density = -math.inf
        self._next_annotations = -math.inf
        self._drawn: Annotations | None = None
        self._next_camera = -math.inf
        self._next_scene = -math.inf
        self._next_lines = -math.inf
        self._scene_period = 0.0
        self._image_ref: str | None = None
        self._grid_key: tuple[float, ...] | None = None
        self._grid_pts: NDArray[np.float64] | None = None
        from swarmdeck.console.recording.recorder import encode_json

        self._json = encode_json

    # ------------------------------------------------------------------ helpers
    def _ts(self, ns: int) -> Any:
        return self.fm.Timestamp(ns // 1_000_000_000, ns % 1_000_000_000)

    def _color(self, rgb: Any, a: float = 1.0) -> Any:
        return self.fm.Color(r=float(rgb[0]) / 255.0, g=float(rgb[1]) / 255.0, b=float(rgb[2]) / 255.0, a=a)

    def _line_list(self, segs: NDArray[np.float64], z: float, thickness: float, color: Any,
                   colors: list[Any] | None = None) -> Any:
        """A LINE_LIST primitive from (K, 2, 2) segments (m) at height z."""
        fm = self.fm
        flat = np.asarray(segs, dtype=float).reshape(-1, 2).tolist()
        return fm.LinePrimitive(type=fm.LinePrimitiveLineType.LineList, thickness=thickness, scale_invariant=False,
                                points=[fm.Point3(x=x, y=y, z=z) for x, y in flat], color=color,
                                colors=colors or [])

    def _entity(self, ns: int, eid: str, **prims: Any) -> Any:
        return self.fm.SceneEntity(timestamp=self._ts(ns), frame_id=ARENA_FRAME, id=eid, **prims)

    def _scene(self, *entities: Any) -> bytes:
        return self.fm.SceneUpdate(entities=list(entities)).encode()

    # ------------------------------------------------------------------ channels
    def robots(self, frame: Frame, ns: int) -> bytes:
        """SceneUpdate: the arena boundary and the robots (discs, heading arrows, id labels) in the
        picture's colours (:func:`~swarmdeck.console.picture.picture.robot_colors`)."""
        fm = self.fm
        x0, x1, y0, y1 = self.bounds
        border = fm.LinePrimitive(type=fm.LinePrimitiveLineType.LineLoop, thickness=0.01,
                                  points=[fm.Point3(x=x, y=y, z=0.0) for x, y in ((x0, y0), (x1, y0), (x1, y1), (x0, y1))],
                                  color=self._color(BOUNDARY))
        p = frame.poses
        xs, ys = p[:, 0].tolist(), p[:, 1].tolist()
        half = 0.5 * p[:, 2]
        qz, qw = np.sin(half).tolist(), np.cos(half).tolist()
        cols = [self._color(c) for c in robot_colors(frame, self.picture)]
        r = self.radius
        disc = fm.Vector3(x=2 * r, y=2 * r, z=0.03)
        cyl = [fm.CylinderPrimitive(pose=fm.Pose(position=fm.Vector3(x=x, y=y, z=0.015),
                                                 orientation=fm.Quaternion(z=z, w=w)),
                                    size=disc, bottom_scale=1.0, top_scale=1.0, color=c)
               for x, y, z, w, c in zip(xs, ys, qz, qw, cols)]
        white = self._color(HEADING)
        arrows = [fm.ArrowPrimitive(pose=fm.Pose(position=fm.Vector3(x=x, y=y, z=0.035),
                                                 orientation=fm.Quaternion(z=z, w=w)),
                                    shaft_length=0.8 * r, shaft_diameter=0.2 * r, head_length=0.5 * r,
                                    head_diameter=0.5 * r, color=white)
                  for x, y, z, w in zip(xs, ys, qz, qw)]
        texts = []
        if self.config.labels and frame.n <= self.config.max_labels:
            ink = self._color(LABEL)
            texts = [fm.TextPrimitive(pose=fm.Pose(position=fm.Vector3(x=x, y=y + 1.4 * r, z=0.05)),
                                      billboard=True, font_size=14.0, scale_invariant=True, color=ink, text=str(i))
                     for x, y, i in zip(xs, ys, frame.ids.tolist())]
        return self._scene(self._entity(ns, "arena", lines=[border, *self._obstacle_lines(frame)]),
                           self._entity(ns, "robots", cylinders=cyl, arrows=arrows, texts=texts))

    def _obstacle_lines(self, frame: Frame | None) -> list[Any]:
        """The frame's line-segment obstacles (the picture's ``obstacles``) as one LINE_LIST, or none."""
        if frame is None or frame.obstacles is None:
            return []
        return [self._line_list(frame.obstacles.segments, 0.005, 0.03, self._color(OBSTACLE))]

    def arena(self, ns: int, frame: Frame | None = None) -> bytes:
        """SceneUpdate: the arena boundary and the ``frame``'s obstacles only (``/foxglove/robots`` of a packed
        recording)."""
        fm = self.fm
        x0, x1, y0, y1 = self.bounds
        border = fm.LinePrimitive(type=fm.LinePrimitiveLineType.LineLoop, thickness=0.01,
                                  points=[fm.Point3(x=x, y=y, z=0.0) for x, y in ((x0, y0), (x1, y0), (x1, y1), (x0, y1))],
                                  color=self._color(BOUNDARY))
        return self._scene(self._entity(ns, "arena", lines=[border, *self._obstacle_lines(frame)]))

    def robot_points(self, frame: Frame, ns: int) -> bytes:
        """PointCloud: one point a robot at disc height, x, y, z, yaw (float32: m, m, m, rad) and its
        picture colour r, g, b, a (uint8), :data:`POINT_STRIDE` bytes a robot, built with numpy."""
        fm = self.fm
        n = frame.n
        rec = np.zeros(n, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("yaw", "<f4"), ("rgba", "u1", 4)])
        rec["x"], rec["y"], rec["yaw"] = frame.poses[:, 0], frame.poses[:, 1], frame.poses[:, 2]
        rec["z"] = 0.015
        rec["rgba"][:, :3] = np.asarray(robot_colors(frame, self.picture), dtype=np.uint8).reshape(n, 3)
        rec["rgba"][:, 3] = 255
        f32, u8 = fm.PackedElementFieldNumericType.Float32, fm.PackedElementFieldNumericType.Uint8
        fields = [fm.PackedElementField(name=k, offset=4 * i, type=f32) for i, k in enumerate(("x", "y", "z", "yaw"))]
        fields += [fm.PackedElementField(name=k, offset=16 + i, type=u8) for i, k in enumerate(("red", "green", "blue", "alpha"))]
        return fm.PointCloud(timestamp=self._ts(ns), frame_id=ARENA_FRAME,
                             pose=fm.Pose(position=fm.Vector3(), orientation=fm.Quaternion(w=1.0)),
                             point_stride=POINT_STRIDE, fields=fields, data=rec.tobytes()).encode()

    def cells(self, frame: Frame, ns: int) -> bytes:
        """SceneUpdate: the Voronoi edges (empty entity when there is no coverage state)."""
        cov = frame.coverage
        lines = []
        if cov is not None and len(cov.edges):
            lines = [self._line_list(cov.edges, 0.002, 0.006, self._color(VORONOI))]
        return self._scene(self._entity(ns, "cells", lines=lines))

    def barrier(self, frame: Frame, ns: int) -> bytes:
        """SceneUpdate: the picture's active barrier pairs between look-ahead points, coloured by h."""
        pairs, h = active_pairs(frame)
        lines = []
        if len(pairs):
            pts = frame.points
            segs = np.stack((pts[pairs[:, 0]], pts[pairs[:, 1]]), axis=1)
            colors = [self._color(c) for c in np.repeat(pair_colors(h, self.picture.h_full), 2, axis=0)]
            lines = [self._line_list(segs, 0.04, 0.012, self._color(PAIR), colors)]
        return self._scene(self._entity(ns, "barrier", lines=lines))

    def sensors(self, frame: Frame, ns: int) -> bytes | None:
        """SceneUpdate: the picture's sensors' layer — ToF rays (a line list) with spheres at their end points and
        each lit LED as a disc on its robot; None when the Frame has no sensors or the layer is off."""
        layer = sensor_layer(frame, self.picture)
        if layer is None:
            return None
        fm = self.fm
        lines = []
        if len(layer.ray_starts):
            lines = [self._line_list(np.stack((layer.ray_starts, layer.ray_ends), axis=1), 0.035, 0.004,
                                     self._color(SENSOR_RAY))]
        size = fm.Vector3(x=0.02, y=0.02, z=0.02)
        hit = self._color(SENSOR_HIT)
        spheres = [fm.SpherePrimitive(pose=fm.Pose(position=fm.Vector3(x=x, y=y, z=0.035)), size=size, color=hit)
                   for x, y in layer.ray_ends.tolist()]
        discs = []
        if layer.leds is not None:
            disc = fm.Vector3(x=self.radius, y=self.radius, z=0.035)
            lit = np.flatnonzero(layer.led_on)
            discs = [fm.CylinderPrimitive(pose=fm.Pose(position=fm.Vector3(x=float(x), y=float(y), z=0.03)), size=disc,
                                          color=self._color(c))
                     for (x, y), c in zip(frame.poses[lit, :2].tolist(), layer.leds[lit].tolist())]
        return self._scene(self._entity(ns, "sensors", lines=lines, spheres=spheres, cylinders=discs))

    def network(self, frame: Frame, ns: int) -> bytes:
        """SceneUpdate: the picture's communication links between robot centres, coloured idle → busy."""
        layer = network_layer(frame, self.picture)
        lines = []
        if layer is not None and len(layer.pairs):
            colors = [self._color(c) for c in np.repeat(layer.colors, 2, axis=0)]
            lines = [self._line_list(layer.segments, 0.003, 0.005, self._color(LINK_IDLE), colors)]
        return self._scene(self._entity(ns, "network", lines=lines))

    def _drawing_changed(self, frame: Frame) -> bool:
        """True when ``frame``'s annotations differ from those last looked at (then remembers them)."""
        a, b = frame.annotations, self._drawn
        same = (a is b) or (a is not None and b is not None and len(a) == len(b) and a.texts == b.texts and all(
            np.array_equal(getattr(a, k), getattr(b, k)) for k in ("kinds", "offsets", "vertices", "sizes", "colors",
                                                                   "filled")))
        self._drawn = a
        return not same

    def annotations(self, frame: Frame, ns: int) -> bytes:
        """SceneUpdate: what the experiment drew (entity ``annotations``, empty when nothing): the picture's
        outlines (:func:`~swarmdeck.console.picture.annotations.annotation_segments`) as one line list,
        filled polygons and circles as triangle fans (convex shapes exact), points as flat spheres, texts as
        texts; colours with their alpha. :meth:`encode` writes it when the drawing changed, else once a second."""
        fm = self.fm
        ann = drawn(frame)  # within the caps, whatever the recording holds
        segs, seg_cols, _ = annotation_segments(ann)
        lines = []
        if len(segs):
            colors = [self._color(c, float(c[3]) / 255.0) for c in np.repeat(seg_cols, 2, axis=0)]
            lines = [self._line_list(segs, 0.003, 0.01, self._color(seg_cols[0], 1.0), colors)]
        dots = ann.kinds == POINT
        spheres = [fm.SpherePrimitive(pose=fm.Pose(position=fm.Vector3(x=x, y=y, z=0.002)),
                                      size=fm.Vector3(x=2 * r, y=2 * r, z=0.002), color=self._color(c, float(c[3]) / 255.0))
                   for (x, y), r, c in zip(ann.vertices[ann.offsets[:-1][dots]].tolist(), ann.sizes[dots].tolist(),
                                           ann.colors[dots])]
        polys, poly_cols = filled_polygons(ann.select(~dots), 16)
        triangles = []
        if polys:
            pts: list[Any] = []
            cols: list[Any] = []
            for poly, c in zip(polys, poly_cols):
                k = len(poly)
                fan = np.stack((np.repeat(poly[:1], k - 2, axis=0), poly[1:-1], poly[2:]), axis=1).reshape(-1, 2)
                pts.extend(fm.Point3(x=x, y=y, z=0.002) for x, y in fan.tolist())
                cols.extend([self._color(c, float(c[3]) / 255.0)] * len(fan))
            triangles = [fm.TriangleListPrimitive(points=pts, colors=cols)]
        anchors, heights, text_cols, strings = annotation_texts(ann)
        texts = [fm.TextPrimitive(pose=fm.Pose(position=fm.Vector3(x=x, y=y, z=0.006)), billboard=True,
                                  font_size=float(h), scale_invariant=False, color=self._color(c, float(c[3]) / 255.0),
                                  text=t)
                 for (x, y), h, c, t in zip(anchors.tolist(), heights.tolist(), text_cols, strings)]
        return self._scene(self._entity(ns, "annotations", lines=lines, triangles=triangles, spheres=spheres,
                                        texts=texts))

    def contacts(self, frame: Frame, ns: int) -> bytes:
        """SceneUpdate: touch contacts as spheres (⌀ 6 cm)."""
        fm = self.fm
        size = fm.Vector3(x=0.06, y=0.06, z=0.06)
        col = self._color(CONTACT, 0.8)
        spheres = [fm.SpherePrimitive(pose=fm.Pose(position=fm.Vector3(x=x, y=y, z=0.03)), size=size, color=col)
                   for x, y in frame.contacts.positions.tolist()]
        return self._scene(self._entity(ns, "contacts", spheres=spheres))

    def poses(self, frame: Frame, ns: int) -> bytes:
        """PosesInFrame: [x, y, θ] of every robot in ``arena``."""
        fm = self.fm
        p = frame.poses
        half = 0.5 * p[:, 2]
        poses = [fm.Pose(position=fm.Vector3(x=x, y=y), orientation=fm.Quaternion(z=z, w=w))
                 for x, y, z, w in zip(p[:, 0].tolist(), p[:, 1].tolist(), np.sin(half).tolist(), np.cos(half).tolist())]
        return fm.PosesInFrame(timestamp=self._ts(ns), frame_id=ARENA_FRAME, poses=poses).encode()

    def density(self, frame: Frame, ns: int) -> bytes | None:
        """Grid of φ (float32 ``phi``, row-major from (x_min, y_min), rows along +y), or None without a density."""
        if frame.density is None:
            return None
        fm = self.fm
        x0, x1, y0, y1 = b = self.bounds
        cell = self.config.density_cell
        w, h = max(1, int(round(b.width / cell))), max(1, int(round(b.height / cell)))
        dx, dy = b.width / w, b.height / h
        key = (x0, x1, y0, y1, cell)
        if self._grid_key != key or self._grid_pts is None:
            gx, gy = np.meshgrid(x0 + (np.arange(w) + 0.5) * dx, y0 + (np.arange(h) + 0.5) * dy)
            self._grid_pts, self._grid_key = np.stack((gx, gy), axis=-1), key
        phi = np.asarray(frame.density.evaluate(self._grid_pts), dtype="<f4")
        return fm.Grid(timestamp=self._ts(ns), frame_id=ARENA_FRAME,
                       pose=fm.Pose(position=fm.Vector3(x=x0, y=y0, z=-0.002), orientation=fm.Quaternion(w=1.0)),
                       column_count=w, cell_size=fm.Vector2(x=dx, y=dy), row_stride=4 * w, cell_stride=4,
                       fields=[fm.PackedElementField(name="phi", offset=0,
                                                     type=fm.PackedElementFieldNumericType.Float32)],
                       data=phi.tobytes()).encode()

    def camera(self, frame: Frame, ns: int) -> bytes | None:
        """CompressedImage (JPEG) of the frame's camera picture, or None when there is none."""
        if self.image_provider is None or frame.image_ref is None:
            return None
        got = self.image_provider(frame.image_ref)
        if got is None:
            return None
        import cv2

        img = np.ascontiguousarray(np.asarray(got[0], dtype=np.uint8)[..., ::-1])  # RGB -> BGR for OpenCV
        ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, self.config.camera_quality])
        if not ok:
            return None
        return self.fm.CompressedImage(timestamp=self._ts(ns), frame_id=CAMERA_FRAME, data=buf.tobytes(),
                                       format="jpeg").encode()

    def transforms(self, ns: int) -> bytes:
        """FrameTransforms: world → arena (identity), arena → camera (above the centre, looking down: 180° about x)."""
        fm = self.fm
        cx, cy = self.bounds.centre
        ts = self._ts(ns)
        return fm.FrameTransforms(transforms=[
            fm.FrameTransform(timestamp=ts, parent_frame_id=WORLD_FRAME, child_frame_id=ARENA_FRAME,
                              translation=fm.Vector3(), rotation=fm.Quaternion(w=1.0)),
            fm.FrameTransform(timestamp=ts, parent_frame_id=ARENA_FRAME, child_frame_id=CAMERA_FRAME,
                              translation=fm.Vector3(x=cx, y=cy, z=self.config.camera_height),
                              rotation=fm.Quaternion(x=1.0, w=0.0)),
        ]).encode()

    def log(self, ns: int, text: str, level: str = "info", name: str = "swarmdeck") -> bytes:
        """Log message (level "debug" | "info" | "warning" | "error")."""
        lv = {"debug": self.fm.LogLevel.Debug, "info": self.fm.LogLevel.Info, "warning": self.fm.LogLevel.Warning,
              "error": self.fm.LogLevel.Error}[level]
        return self.fm.Log(timestamp=self._ts(ns), level=lv, message=str(text), name=name).encode()

    def metrics(self, frame: Frame, t: float) -> bytes:
        """The plottable scalars of :data:`METRIC_FIELDS` as JSON."""
        b, cov = frame.barrier, frame.coverage
        inter = b.intervention if b is not None else np.zeros(0)
        total = frame.timing.get("total")
        out = {
            "t": _num(t), "tick": frame.tick,
            "min_distance_m": _num(b.min_distance) if b is not None else None,
            "safety_distance_m": _num(b.safety_distance) if b is not None else None,
            "min_wall_clearance_m": _num(b.min_wall_clearance) if b is not None else None,
            "n_active": b.n_active if b is not None else None,
            "robots_changed": int(np.count_nonzero(changed_mask(frame, self.picture))) if b is not None else None,
            "max_intervention_mps": _num(inter.max()) if len(inter) else None,
            "solve_time_ms": _num(1e3 * b.solve_time_s) if b is not None else None,
            "cost_H": _num(cov.cost_H) if cov is not None else None,
            "mean_centroid_distance_m": _num(cov.mean_centroid_distance) if cov is not None else None,
            "tick_time_ms": _num(1e3 * total) if total is not None else None,
        }
        return self._json(out)

    # ------------------------------------------------------------------ one frame
    def encode(self, frame: Frame, ns: int, t: float) -> Iterator[tuple[str, int, bytes]]:
        """Every message of ``frame`` logged at ``ns`` (Unix ns); ``t`` its recording time, s."""
        yield TOPIC_TF, ns, self.transforms(ns)
        # per-robot channels at most every scene_period(N) s; half a frame of slack so that a period
        # of one frame period is every frame despite rounding of the frame times
        if frame.time + 0.5 * frame.dt >= self._next_scene or frame.time < self._next_scene - 2 * self._scene_period:
            self._scene_period = self.config.scene_period(frame.n)
            self._next_scene = frame.time + self._scene_period
            if self.config.packed:
                yield TOPIC_ROBOTS, ns, self.arena(ns, frame)
                yield TOPIC_ROBOT_POINTS, ns, self.robot_points(frame, ns)
            else:
                yield TOPIC_ROBOTS, ns, self.robots(frame, ns)
                yield TOPIC_POSES, ns, self.poses(frame, ns)
            if frame.time + 0.5 * frame.dt >= self._next_lines or frame.time < self._next_lines - 2 * max(
                    self._scene_period, self.config.lines_period):
                self._next_lines = frame.time + self.config.lines_period
                yield TOPIC_CELLS, ns, self.cells(frame, ns)
                yield TOPIC_BARRIER, ns, self.barrier(frame, ns)
                if frame.network is not None:
                    yield TOPIC_NETWORK, ns, self.network(frame, ns)
                if self._drawing_changed(frame) or frame.time >= self._next_annotations or \
                        frame.time < self._next_annotations - 2.0:
                    self._next_annotations = frame.time + 1.0
                    yield TOPIC_ANNOTATIONS, ns, self.annotations(frame, ns)
            if frame.sensors is not None:
                data = self.sensors(frame, ns)
                if data is not None:
                    yield TOPIC_SENSORS, ns, data
        yield TOPIC_CONTACTS, ns, self.contacts(frame, ns)
        yield TOPIC_METRICS, ns, self.metrics(frame, t)
        if frame.density is not None and frame.time >= self._next_density:
            data = self.density(frame, ns)
            if data is not None:
                yield TOPIC_DENSITY, ns, data
            self._next_density = frame.time + self.config.density_period
        if frame.image_ref is not None and frame.image_ref != self._image_ref and frame.time >= self._next_camera:
            data = self.camera(frame, ns)
            if data is not None:
                self._image_ref = frame.image_ref
                self._next_camera = frame.time + self.config.camera_period
                yield TOPIC_CAMERA, ns, data
        for text in frame.events:
            yield TOPIC_LOG, ns, self.log(ns, text)
        alerts = frozenset(frame.alerts)
        for text in sorted(alerts - self._alerts):
            yield TOPIC_LOG, ns, self.log(ns, text, "warning")
        for text in sorted(self._alerts - alerts):
            yield TOPIC_LOG, ns, self.log(ns, f"cleared: {text}")
        self._alerts = alerts
