"""The arena drawn in viser, top-down, as a function of Frames (live or played back).

:class:`ArenaScene` owns the scene nodes under ``/arena``, ``/density``,
``/voronoi``, ``/robots``, … of one viser server and updates them in place from
a :class:`~swarmdeck.console.runtime.frame.Frame` inside a single ``server.atomic()``
block per call to :meth:`ArenaScene.draw`. It keeps no state that a Frame does
not give, except the trails (the last positions of consecutive Frames; a jump
in the tick index resets them) and the geometry caches that depend on N.

Layers (``LAYERS``), each toggleable with :meth:`ArenaScene.set_layer`:
camera (the rectified overhead image of the Frame's ``image_ref``, when an
image provider is given; the density heat map is then drawn translucent over
it), grid, density heat map, Voronoi edges, filled cells, centroids, robots,
labels, nominal arrows, safe arrows, barrier pairs, safety discs, trails,
contacts, goals (green crosses at the goals of ``goto``, from the Frame's params),
virtual (a dashed violet ring around each virtual robot, which is
also drawn pale), battery (a bar under each robot that reports its battery: its
length the state of charge, green/amber/red by level, blue while charging, on a
grey full-length track; :mod:`swarmdeck.console.runtime.batteries`), network (the robots' communication
links of a decentralised run, pale when idle, cyan by messages per second; :mod:`swarmdeck.console.picture.network`),
annotations (what the experiment drew: :mod:`swarmdeck.console.web.scene_annotations`). It scales to a thousand robots: robots are one batched mesh and the
Voronoi edges one line-segment node whatever N; labels exist only up to
``SceneStyle.max_labels`` robots and the per-robot glyphs (arrows, safety discs,
trails) only up to ``max_glyphs``; the heat map keeps under ``heatmap_max_px`` pixels. Colours: robots blue; robots whose command the barrier changed
orange; stopped (emergency stop) red; paused slate; not seen grey; virtual robots
the same colours blended 55 % toward white.

What to draw comes from the renderer-neutral picture of the Frame
(:func:`~swarmdeck.console.picture.picture.picture_of`: colours, changed robots, active pairs,
rings, arrow tips, labels, heat map, cells), which the video, the Foxglove channels and the
portal's live view draw too; this module only turns it into viser nodes.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.console.picture.colours import (  # noqa: F401 - the palette, re-exported for the scene's callers
    BATTERY_COLORS,
    BATTERY_TRACK,
    BOUNDARY,
    CENTROID,
    CHANGED,
    CONTACT,
    GOAL,
    LINK_IDLE,
    LUT,
    NOMINAL,
    OBSTACLE,
    PAIR,
    PAUSED,
    ROBOT,
    SAFE,
    SAFETY_RING,
    SENSOR_RAY,
    STOPPED,
    UNSEEN,
    VIRTUAL_PALE,
    VIRTUAL_RING,
    VORONOI,
)
from swarmdeck.console.picture.heat import heatmap  # noqa: F401 - re-exported for the scene's callers
from swarmdeck.console.picture.picture import Picture, picture_of, robot_colors
from swarmdeck.console.picture.shapes import dashed_rings, robot_outline
from swarmdeck.console.picture.style import PictureStyle
from swarmdeck.console.runtime.frame import Frame, filled
from swarmdeck.console.web.scene_annotations import AnnotationNodes
from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.constants import ROBOT_RADIUS

if TYPE_CHECKING:
    import viser

ImageProvider = Callable[[str], "tuple[ArrayLike, tuple[float, float, float, float]] | None"]
"""Maps a Frame's ``image_ref`` to (RGB image (H, W, 3), its bounds (x0, x1, y0, y1) m), or None."""

LAYERS: tuple[str, ...] = (
    "camera", "grid", "density", "voronoi", "cells", "centroids", "robots", "labels", "nominal", "safe",
    "barrier", "discs", "trails", "contacts", "virtual", "battery", "goals", "sensors", "obstacles", "network",
    "annotations",
)
DEFAULT_OFF = frozenset({"cells"})

_EMPTY_SEG = np.array([[[0.0, 0.0, -5.0], [0.0, 0.0, -5.0]]], dtype=np.float32)
_PER_ROBOT_GLYPHS = frozenset({"nominal", "safe", "discs", "trails"})  # hidden above SceneStyle.max_glyphs robots


@dataclass(frozen=True)
class SceneStyle(PictureStyle):
    """The picture's rules (:class:`~swarmdeck.console.picture.style.PictureStyle`: changed threshold, pair
    colours, labels and glyphs up to how many robots, heat-map sampling, arrow scale) plus the viser scene's
    own sizes in m (world units) and sampling."""

    trail_length: int = 40
    trail_every: int = 3  # ticks between trail samples
    disc_segments: int = 20
    overlay_alpha: tuple[float, float] = (0.15, 0.6)  # heat map opacity over the camera picture, φ = 0 … max φ
    panel_shift: float = 0.24  # the top view's shift right, × view height, clearing the control panel (0: centred)


def robot_mesh(radius: float) -> tuple[NDArray[np.float32], NDArray[np.uint32]]:
    """The picture's teardrop (:func:`~swarmdeck.console.picture.shapes.robot_outline`) as a flat fan
    mesh: vertices (V, 3), faces (F, 3)."""
    rim = robot_outline(radius)
    verts = np.vstack(([[0.0, 0.0]], rim))
    verts = np.column_stack((verts, np.zeros(len(verts)))).astype(np.float32)
    m = len(rim)
    faces = np.array([[0, 1 + i, 1 + (i + 1) % m] for i in range(m)], dtype=np.uint32)
    return verts, faces


def _segments_2d(a: NDArray[np.float64], b: NDArray[np.float64], z: float) -> NDArray[np.float32]:
    """(K, 2, 3) segments from (K, 2) starts and ends at height z; a hidden stub when K = 0."""
    if len(a) == 0:
        return _EMPTY_SEG
    out = np.empty((len(a), 2, 3), dtype=np.float32)
    out[:, 0, :2], out[:, 1, :2] = a, b
    out[:, :, 2] = z
    return out


def _yaw_wxyz(theta: NDArray[np.float64]) -> NDArray[np.float32]:
    h = 0.5 * theta
    return np.column_stack((np.cos(h), np.zeros_like(h), np.zeros_like(h), np.sin(h))).astype(np.float32)


def battery_bars(frame: Frame, robot_radius: float) -> tuple[NDArray[np.float32], NDArray[np.uint8]]:
    """Battery bars of the robots reporting one (K of them): segments (2K, 2, 3) — a grey track of
    2.2 robot radii, then the level bar from its left end, as long as the state of charge —
    and their colours (2K, 2, 3) (:data:`BATTERY_COLORS`). A hidden stub when nobody reports."""
    from swarmdeck.console.runtime.batteries import battery_levels

    q, level = battery_levels(filled(frame.battery), filled(frame.charging))
    known = np.flatnonzero(~np.isnan(q))
    if not len(known):
        return _EMPTY_SEG, np.repeat(BATTERY_TRACK[None, None], 2, axis=1)
    half = 1.1 * robot_radius
    left = frame.poses[known, :2] + np.array([-half, -1.6 * robot_radius])
    track_end = left + [2 * half, 0.0]
    fill_end = left + np.column_stack((2 * half * np.maximum(q[known], 0.04), np.zeros(len(known))))
    segs = np.concatenate((_segments_2d(left, track_end, 0.013), _segments_2d(left, fill_end, 0.014)))
    cols = np.concatenate((np.tile(BATTERY_TRACK, (len(known), 1)), BATTERY_COLORS[level[known]]))
    return segs, np.repeat(cols[:, None, :], 2, axis=1)


PointLayer = Literal["centroids", "contacts", "goals"]
"""The layers drawn as point clouds (:meth:`SceneNodes.point_layer`)."""


@dataclass
class SceneNodes:
    """The scene nodes the :class:`ArenaScene` updates, one field per layer (``LAYERS``; ``grid`` is the
    floor grid, ``boundary`` the arena outline). ``robots`` exists from the first Frame on; ``cells``
    only while that layer is shown and a Frame has cells; ``camera`` from the first camera image."""

    boundary: viser.LineSegmentsHandle
    grid: viser.GridHandle
    density: viser.ImageHandle
    voronoi: viser.LineSegmentsHandle
    centroids: viser.PointCloudHandle
    trails: viser.LineSegmentsHandle
    discs: viser.LineSegmentsHandle
    barrier: viser.LineSegmentsHandle
    nominal: viser.ArrowsHandle
    safe: viser.ArrowsHandle
    contacts: viser.PointCloudHandle
    virtual: viser.LineSegmentsHandle
    battery: viser.LineSegmentsHandle
    goals: viser.PointCloudHandle
    annotations: AnnotationNodes
    sensors: viser.LineSegmentsHandle | None = None  # the ToF rays (issue 28.1); made with the static nodes
    leds: viser.PointCloudHandle | None = None  # lit LEDs, shown with the sensors layer
    network: viser.LineSegmentsHandle | None = None  # the communication graph (made by _setup_static)
    robots: viser.BatchedMeshHandle | None = None
    cells: viser.GlbHandle | None = None
    camera: viser.ImageHandle | None = None
    labels: list[viser.LabelHandle] = field(default_factory=list)
    obstacles: viser.LineSegmentsHandle | None = None  # from the first Frame with obstacles (static in a run)

    def layer(self, name: str) -> viser.SceneNodeHandle | None:
        """The node of layer ``name`` (None while it has none; ``labels`` is a list: not here)."""
        return getattr(self, name)

    def point_layer(self, name: PointLayer) -> viser.PointCloudHandle:
        """The point-cloud node of the point layer ``name`` (made with the scene: never None)."""
        handle: viser.PointCloudHandle = getattr(self, name)
        return handle


class ArenaScene:
    """Draw Frames into ``server.scene`` (shared by every browser tab). See the module docstring.

    Args:
        server: the viser server whose ``scene`` is drawn into.
        bounds: the arena rectangle (x_min, x_max, y_min, y_max), m.
        robot_radius: body radius for the robot glyph, m.
        style: sizes and sampling.
        root: a prefix of every node's name (``/runB``: the scene of a run drawn beside others, moved as one by
            the frame node ``/runB``; ``swarmdeck play A B --layout side``).
    """

    def __init__(self, server: viser.ViserServer, bounds: Bounds = DEFAULT_BOUNDS,
                 robot_radius: float = ROBOT_RADIUS, style: SceneStyle | None = None,
                 image_provider: ImageProvider | None = None, root: str = "") -> None:
        self.server = server
        self.root = root  # every node's name starts with it ("" — the console; "/runB" — a run beside others)
        self.image_provider = image_provider
        self._image_ref: str | None = None
        self.scene = server.scene
        self.bounds: Bounds = Bounds(*(float(b) for b in bounds))
        self.style = style or SceneStyle()
        self.robot_radius = robot_radius
        self.visible = {name: name not in DEFAULT_OFF for name in LAYERS}
        self._empty = {"contacts": True, "centroids": True, "goals": True}  # point layers with no point this frame
        self._n = -1
        self._many = False
        self._last_tick: int | None = None
        self._trail: NDArray[np.float64] | None = None
        self._trail_count = 0
        self.frames_drawn = 0
        self._obstacles: object = None  # the Frame.obstacles drawn (static in a run: redrawn only when they change)
        self._setup_static()

    # ------------------------------------------------------------------ setup
    def look_at(self, bounds: Bounds) -> None:
        """Point the initial camera top-down at ``bounds`` (x_min, x_max, y_min, y_max, m): the arena, or the
        row of arenas of runs shown side by side."""
        (cx, cy), w, h = bounds.centre, bounds.width, bounds.height
        # Top-down: a narrow perspective from high above (viser has no orthographic camera). The view
        # is shifted right by ~half the control panel so the arena sits in the visible part of a
        # 1280×800 window (REFERENCE.md §8).
        cam = self.server.initial_camera
        fov = math.radians(20.0)
        view_h = max(h, w / 1.1) * 1.17
        cam.fov = fov
        shift = self.style.panel_shift * view_h
        cam.look_at = (cx + shift, cy, 0.0)
        cam.position = (cx + shift, cy, 0.5 * view_h / math.tan(fov / 2))
        cam.up = (0.0, 1.0, 0.0)

    def _setup_static(self) -> None:
        sc = self.scene
        x0, x1, y0, y1 = self.bounds
        (cx, cy), w, h = self.bounds.centre, self.bounds.width, self.bounds.height
        sc.configure_environment_map(None)
        sc.set_up_direction("+z")
        self.look_at(self.bounds)
        corners = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
        boundary = sc.add_line_segments(
            f"{self.root}/arena/boundary", _segments_2d(corners, np.roll(corners, -1, axis=0), 0.004), BOUNDARY,
            thickness=0.015)
        grid = sc.add_grid(f"{self.root}/arena/grid", width=w, height=h, plane="xy", cell_size=0.1, section_size=0.5,
                           cell_color=(215, 215, 215), section_color=(170, 170, 170),
                           position=(cx, cy, -0.004), shadow_opacity=0.0)
        blank = np.full((8, 8, 3), 250, dtype=np.uint8)
        # format "auto": JPEG for the opaque heat map, PNG (keeps alpha) for the translucent one over the
        # camera picture, which lies below it (z = -0.012)
        density_image = sc.add_image(f"{self.root}/density", blank, render_width=w, render_height=h, format="auto",
                                     jpeg_quality=90, position=(cx, cy, -0.01), wxyz=(0.0, 1.0, 0.0, 0.0),
                                     cast_shadow=False, receive_shadow=False)
        voronoi = sc.add_line_segments(f"{self.root}/voronoi", _EMPTY_SEG, VORONOI, thickness=0.006)
        centroids = sc.add_point_cloud(f"{self.root}/centroids", np.zeros((1, 3), np.float32) - [0, 0, 5],
                                       CENTROID, point_size=0.035, point_shape="diamond",
                                       precision="float32")
        trails = sc.add_line_segments(f"{self.root}/trails", _EMPTY_SEG, (120, 160, 220), thickness=0.006)
        discs = sc.add_line_segments(f"{self.root}/discs", _EMPTY_SEG, SAFETY_RING, thickness=0.004)
        barrier = sc.add_line_segments(f"{self.root}/barrier", _EMPTY_SEG, PAIR, thickness=0.014)
        stub = np.array([[[0, 0, -5], [0.001, 0, -5]]], dtype=np.float32)
        nominal = sc.add_arrows(f"{self.root}/arrows/nominal", stub, NOMINAL, shaft_radius=0.006,
                                head_radius=0.016, head_length=0.03)
        safe = sc.add_arrows(f"{self.root}/arrows/safe", stub, SAFE, shaft_radius=0.007,
                             head_radius=0.018, head_length=0.03)
        contacts = sc.add_point_cloud(f"{self.root}/contacts", np.zeros((1, 3), np.float32) - [0, 0, 5],
                                      CONTACT, point_size=0.07, point_shape="circle",
                                      precision="float32")
        virtual = sc.add_line_segments(f"{self.root}/virtual", _EMPTY_SEG, VIRTUAL_RING, thickness=0.008)
        battery = sc.add_line_segments(f"{self.root}/battery", _EMPTY_SEG, BATTERY_TRACK, thickness=0.018)
        goals = sc.add_point_cloud(f"{self.root}/goals", np.zeros((1, 3), np.float32), GOAL, point_size=0.05,
                                   point_shape="diamond", precision="float32", visible=False)
        sensors = sc.add_line_segments(f"{self.root}/sensors/rays", _EMPTY_SEG, SENSOR_RAY, thickness=0.003)
        leds = sc.add_point_cloud(f"{self.root}/sensors/leds", np.zeros((1, 3), np.float32) - [0, 0, 5], (0, 0, 0),
                                  point_size=0.045, point_shape="circle", precision="float32")
        self.nodes = SceneNodes(boundary=boundary, grid=grid, density=density_image, voronoi=voronoi,
                                centroids=centroids, trails=trails, discs=discs, barrier=barrier,
                                nominal=nominal, safe=safe, contacts=contacts, virtual=virtual, battery=battery,
                                goals=goals, sensors=sensors, leds=leds, annotations=AnnotationNodes(sc, root=self.root))
        self.nodes.network = sc.add_line_segments(f"{self.root}/network", _EMPTY_SEG, LINK_IDLE, thickness=0.005)
        for name in LAYERS:
            self._apply_visibility(name)

    def _setup_robots(self, frame: Frame) -> None:
        n = frame.n
        sc = self.scene
        verts, faces = robot_mesh(self.robot_radius)
        pos = np.column_stack((frame.poses[:, :2], np.full(n, 0.01))).astype(np.float32)
        self.nodes.robots = sc.add_batched_meshes_simple(
            f"{self.root}/robots", verts, faces, batched_wxyzs=_yaw_wxyz(frame.poses[:, 2]), batched_positions=pos,
            batched_colors=robot_colors(frame), flat_shading=True, cast_shadow=False, receive_shadow=False)
        for lab in self.nodes.labels:
            lab.remove()
        self.nodes.labels = [
            sc.add_label(f"{self.root}/labels/r{int(i)}", str(int(i)), position=(float(p[0]), float(p[1]) + self.style.label_offset, 0.02),
                         font_size_mode="screen", font_screen_scale=0.8, anchor="center-center",
                         visible=self.visible["labels"])
            for i, p in zip(frame.ids, frame.poses)
        ] if n <= self.style.max_labels else []  # a thousand label nodes would swamp the browser
        self._many = n > self.style.max_glyphs
        for name in ("nominal", "safe", "discs", "trails"):  # per-robot glyphs: only for small swarms
            self._apply_visibility(name)
        self._label_xy = frame.poses[:, :2].copy()
        self._n = n
        self._trail = None
        self._apply_visibility("robots")

    # ------------------------------------------------------------------ layers
    def _apply_visibility(self, name: str) -> None:
        if name in self._empty and self._empty[name]:  # nothing to draw: hidden, not a placeholder under the floor
            node = self.nodes.layer(name)
            if node is not None:
                node.visible = False
            return
        if name == "labels":
            for lab in self.nodes.labels:
                lab.visible = self.visible["labels"]
            return
        h = self.nodes.layer(name)
        if h is not None:
            h.visible = self.visible[name] and not (self._many and name in _PER_ROBOT_GLYPHS)
        if name == "sensors" and self.nodes.leds is not None:
            self.nodes.leds.visible = self.visible[name]

    def _draw_obstacles(self, pic: Picture) -> None:
        """The line-segment obstacles (``pic.obstacles``, m) as thick segments just above the floor."""
        seg = pic.obstacles
        if self.nodes.obstacles is not None:
            self.nodes.obstacles.remove()
            self.nodes.obstacles = None
        if len(seg):
            self.nodes.obstacles = self.scene.add_line_segments(
                f"{self.root}/obstacles", _segments_2d(seg[:, 0], seg[:, 1], 0.005), OBSTACLE, thickness=0.03)
            self._apply_visibility("obstacles")

    def set_layer(self, name: str, visible: bool) -> None:
        """Show or hide one layer (``LAYERS``); ValueError for unknown names."""
        if name not in LAYERS:
            raise ValueError(f"unknown layer {name!r}; layers are {', '.join(LAYERS)}")
        self.visible[name] = bool(visible)
        if name == "cells" and not visible and self.nodes.cells is not None:
            self.nodes.cells.remove()
            self.nodes.cells = None
        self._apply_visibility(name)

    # ------------------------------------------------------------------ drawing
    def draw(self, frame: Frame) -> None:
        """Update every visible layer from ``frame`` in one atomic viser update."""
        with self.server.atomic():
            self._draw(frame)
        self.frames_drawn += 1

    def _draw(self, frame: Frame) -> None:
        v = self.visible
        st = self.style
        if frame.n != self._n:
            self._setup_robots(frame)
        pic = picture_of(frame, st)
        pts = pic.points
        poses = frame.poses
        if frame.obstacles != self._obstacles:
            self._draw_obstacles(pic)
            self._obstacles = frame.obstacles
        if v["robots"]:
            robots = self.nodes.robots
            assert robots is not None  # made by _setup_robots above
            robots.batched_positions = np.column_stack((poses[:, :2], np.full(frame.n, 0.01))).astype(np.float32)
            robots.batched_wxyzs = _yaw_wxyz(poses[:, 2])
            robots.batched_colors = pic.colors
        if v["labels"] and self.nodes.labels:  # no labels above SceneStyle.max_labels robots
            # One message per label, in the same atomic update as the robots: every label whose robot
            # moved at all is moved to it (a "moved enough" threshold left labels trailing their robots).
            moved = np.flatnonzero(np.any(poses[:, :2] != self._label_xy, axis=1))
            for i in moved:
                self.nodes.labels[i].position = (float(pic.label_xy[i, 0]), float(pic.label_xy[i, 1]), 0.02)
            self._label_xy[moved] = poses[moved, :2]
        if v["camera"] and frame.image_ref is not None and self.image_provider is not None \
                and frame.image_ref != self._image_ref:
            self._draw_camera(frame.image_ref)
        if v["density"] and pic.density is not None:
            over_camera = v["camera"] and self.nodes.camera is not None
            image = pic.heat_map(st.heatmap_px(self.bounds), st.overlay_alpha if over_camera else None)
            assert image is not None  # the Frame has a density
            self.nodes.density.image = image
        if v["voronoi"]:
            self.nodes.voronoi.points = _segments_2d(pic.edges[:, 0], pic.edges[:, 1], 0.003)
        if v["centroids"]:
            self._points("centroids", pic.centroids, 0.006)
        if v["cells"]:
            self._draw_cells(pic)
        glyphs = not self._many
        if v["nominal"] and glyphs:
            self.nodes.nominal.points = self._arrows(pts, pic.nominal_tips, frame.nominal, 0.02)
        if v["safe"] and glyphs:
            self.nodes.safe.points = self._arrows(pts, pic.safe_tips, frame.safe, 0.025)
        if v["barrier"]:
            pair_lines = self.nodes.barrier
            if len(pic.pairs):
                pair_lines.points = _segments_2d(pts[pic.pairs[:, 0]], pts[pic.pairs[:, 1]], 0.008)
                pair_lines.colors = np.repeat(pic.pair_colors[:, None, :], 2, axis=1)
            else:
                pair_lines.points = _EMPTY_SEG
                pair_lines.colors = np.array(PAIR, dtype=np.uint8)
        if v["discs"] and glyphs:
            self.nodes.discs.points = self._discs(pts, pic.ring_radius)
        self._update_trails(frame)  # accumulates even while hidden, so showing trails is instant
        if v["virtual"]:
            self.nodes.virtual.points = self._virtual_rings(poses[pic.virtual, :2])
        if v["battery"]:
            segs, cols = battery_bars(frame, self.robot_radius)
            self.nodes.battery.points, self.nodes.battery.colors = segs, cols
        if v["contacts"]:
            self._points("contacts", pic.contacts, 0.012)
        if v["goals"]:
            self._points("goals", pic.goals, 0.002)
        if v["sensors"]:
            self._draw_sensors(pic)
        if v["network"] and self.nodes.network is not None:
            self._draw_network(pic)
        if v["annotations"] and (len(pic.annotations) or self.nodes.annotations.drawn):
            self.nodes.annotations.draw(pic.annotations)

    def _draw_sensors(self, pic: Picture) -> None:
        """The picture's sensors' layer: ToF rays from sensor to end point, lit LEDs as coloured points."""
        rays, leds = self.nodes.sensors, self.nodes.leds
        assert rays is not None and leds is not None  # made with the static nodes
        layer = pic.sensors
        if layer is None or not len(layer.ray_starts):
            rays.points = _EMPTY_SEG
        else:
            rays.points = _segments_2d(layer.ray_starts, layer.ray_ends, 0.02)
        lit = np.zeros(0, dtype=np.intp) if layer is None or layer.leds is None else np.flatnonzero(layer.led_on)
        if len(lit) and layer is not None and layer.leds is not None:
            leds.points = np.column_stack((pic.poses[lit, :2], np.full(len(lit), 0.03))).astype(np.float32)
            leds.colors = layer.leds[lit]
        else:
            leds.points = np.zeros((1, 3), np.float32) - np.array([0, 0, 5], np.float32)

    def _draw_network(self, pic: Picture) -> None:
        """The picture's communication links (:mod:`~swarmdeck.console.picture.network`), idle → busy colours."""
        node = self.nodes.network
        assert node is not None
        layer = pic.network
        if layer is None or not len(layer.pairs):
            node.points, node.colors = _EMPTY_SEG, np.array(LINK_IDLE, dtype=np.uint8)
            return
        node.points = _segments_2d(layer.segments[:, 0], layer.segments[:, 1], 0.001)
        node.colors = np.repeat(layer.colors[:, None, :], 2, axis=1)

    def _points(self, name: PointLayer, xy: NDArray[np.float64], z: float) -> None:
        """Put ``xy`` (K, 2) m at height ``z`` into the point layer ``name``; with no point the node is hidden."""
        was_empty, self._empty[name] = self._empty[name], not len(xy)
        if len(xy):
            self.nodes.point_layer(name).points = np.column_stack((xy, np.full(len(xy), z))).astype(np.float32)
        if was_empty != self._empty[name]:
            self._apply_visibility(name)

    def _draw_camera(self, ref: str) -> None:
        """The overhead image (RGB, row 0 at y_max, covering its bounds) just below the heat map, which
        is then drawn translucent over it."""
        got = None if self.image_provider is None else self.image_provider(ref)
        if got is None:
            return
        img, covered = got
        area = Bounds.of(covered)
        self._image_ref = ref
        h = self.nodes.camera
        if h is None:
            self.nodes.camera = self.scene.add_image(
                f"{self.root}/camera", np.asarray(img), render_width=area.width, render_height=area.height, format="jpeg",
                jpeg_quality=80, position=(*area.centre, -0.012), wxyz=(0.0, 1.0, 0.0, 0.0),
                cast_shadow=False, receive_shadow=False, visible=self.visible["camera"])
        else:
            h.image = np.asarray(img)

    @staticmethod
    def _arrows(start: NDArray[np.float64], tips: NDArray[np.float64], u: NDArray[np.float64],
                z: float) -> NDArray[np.float32]:
        """Arrows from ``start`` to the picture's ``tips`` (N, 2) m at height ``z``; a command ``u`` below
        0.1 mm/s gets a stub (viser cannot draw a zero-length arrow), all hidden when every one is a stub."""
        end = np.array(tips, dtype=float)
        tiny = np.linalg.norm(u, axis=1) < 1e-4
        end[tiny] = start[tiny] + np.array([1e-4, 0.0])
        out = np.empty((len(start), 2, 3), dtype=np.float32)
        out[:, 0, :2], out[:, 1, :2] = start, end
        out[:, :, 2] = z
        if tiny.all():
            out[:, :, 2] = -5.0
        return out

    def _virtual_rings(self, centres: NDArray[np.float64]) -> NDArray[np.float32]:
        """The picture's dashed rings (:func:`~swarmdeck.console.picture.shapes.dashed_rings`) round the
        virtual robots ``(K, 2)``."""
        return _segments_2d(*dashed_rings(centres, self.robot_radius), 0.012)

    def _discs(self, centres: NDArray[np.float64], r: float) -> NDArray[np.float32]:
        k = self.style.disc_segments
        a = np.linspace(0, 2 * np.pi, k + 1)
        ring = r * np.column_stack((np.cos(a), np.sin(a)))
        p = centres[:, None, :] + ring[None, :, :]  # (N, k+1, 2)
        return _segments_2d(p[:, :-1].reshape(-1, 2), p[:, 1:].reshape(-1, 2), 0.002)

    def _update_trails(self, frame: Frame) -> None:
        st = self.style
        L = st.trail_length
        xy = frame.poses[:, :2]
        consecutive = self._last_tick is not None and frame.tick == self._last_tick + 1
        self._last_tick = frame.tick
        if self._trail is None or not consecutive or self._trail.shape[1] != frame.n:
            self._trail = np.repeat(xy[None], L, axis=0)
            self._trail_count = 0
            self._trail_colors = None
        elif frame.tick % st.trail_every == 0:
            self._trail = np.roll(self._trail, -1, axis=0)
            self._trail[-1] = xy
        else:
            return
        if not self.visible["trails"] or self._many:
            return
        tr = self._trail  # (L, N, 2), oldest first
        a = tr[:-1].transpose(1, 0, 2).reshape(-1, 2)
        b = tr[1:].transpose(1, 0, 2).reshape(-1, 2)
        h = self.nodes.trails
        if self._trail_colors is None:
            fade = np.linspace(0.0, 1.0, L - 1)
            ramp = (np.array([235, 240, 250])[None] * (1 - fade[:, None]) + np.array([70, 120, 210])[None] * fade[:, None])
            c = np.tile(ramp, (frame.n, 1)).astype(np.uint8)
            self._trail_colors = np.repeat(c[:, None, :], 2, axis=1)
        h.points = _segments_2d(a, b, 0.001)
        h.colors = self._trail_colors

    def _draw_cells(self, pic: Picture) -> None:
        old = self.nodes.cells
        if len(pic.cell_offsets) < 2:
            if old is not None:
                old.remove()
                self.nodes.cells = None
            return
        import trimesh

        o = pic.cell_offsets
        verts = np.column_stack((pic.cell_vertices, np.full(len(pic.cell_vertices), -0.006)))
        counts = np.diff(o)
        cell_of = np.repeat(np.arange(len(counts)), np.maximum(counts - 2, 0))
        start = o[cell_of]
        k = np.arange(len(cell_of)) - np.repeat(np.cumsum(np.maximum(counts - 2, 0)) - np.maximum(counts - 2, 0),
                                                np.maximum(counts - 2, 0))
        faces = np.column_stack((start, start + k + 1, start + k + 2))
        shade = pic.cell_shades
        face_colors = np.column_stack((shade[cell_of], np.full(len(cell_of), 90))).astype(np.uint8)
        mesh = trimesh.Trimesh(vertices=verts, faces=faces, face_colors=face_colors, process=False)
        self.nodes.cells = self.scene.add_mesh_trimesh(f"{self.root}/cells", mesh)
