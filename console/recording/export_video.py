"""MP4 video of a recording, drawn top-down like the console's scene (H.264, yuv420p: every browser plays it).

:func:`export_video` samples the recording at ``fps`` frames per second of
recording time (video frame k shows the last recorded Frame at or before
``start + k / fps``, so a recording of D s gives ``floor(D · fps) + 1`` video
frames) and draws each sample with OpenCV on a numpy RGB image:

- the density φ as the console's heat map (``picture.heatmap``, its colour map),
  with the floor grid every 0.5 m and the arena outline;
- the Voronoi edges and centroids of the coverage state;
- barrier activity: active pairs as thick lines between look-ahead points,
  coloured by h like the console (``picture.pair_colors``: red at h ≤ 0 → yellow),
  and an orange ring around every robot whose command the filter changed;
- the robots as the console's teardrop (``picture.shapes.robot_outline``: a disc with a nose
  along the heading) coloured by state (``picture.robot_colors``: blue, orange when
  the filter changed the command, red in an emergency stop, slate paused, grey
  unseen; virtual robots pale, in a dashed violet ring), a white heading tick, and the id above (up to ``PictureStyle.max_labels``
  robots), with the safety discs of radius D_s / 2 up to ``PictureStyle.max_glyphs``;
- touch contacts (magenta dots);
- a header with the recording time (s since the first frame, the time
  ``swarmdeck play`` seeks to), N, the behaviour, the run state and the barrier's
  numbers; "EMERGENCY STOP" in red (and a red frame round the arena) while the
  run is e-stopped; a footer with the events of the last few seconds;
- the overhead camera picture in a panel right of the arena (which then
  shrinks, so the picture never hides a robot) when the recording holds
  camera pictures (the Foxglove channel ``/foxglove/camera``).

Robots are drawn vectorised: one ``fillPoly`` per colour for all bodies, one
``polylines`` for all heading ticks, rings and discs, and the ids as cached
text masks placed with one fancy-indexing assignment.

Encoding uses PyAV (the ``av`` wheels bundle FFmpeg with libx264). The file is
written beside ``out`` and renamed when complete, so a failed export never
leaves a partial video under the requested name.
"""
from __future__ import annotations

import math
import os
from bisect import bisect_left, bisect_right
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.picture.colours import (
    BOUNDARY,
    CENTROID,
    CHANGED,
    CONTACT,
    HEADING,
    LABEL,
    LUT,
    SAFETY_RING,
    SENSOR_HIT,
    SENSOR_RAY,
    STOPPED,
    VIRTUAL_RING,
    VORONOI,
    pair_colors,
)
from swarmdeck.console.picture.heat import heatmap
from swarmdeck.console.picture.picture import Picture, picture_of
from swarmdeck.console.picture.shapes import CHANGED_RING, dashed_rings, robot_outline
from swarmdeck.console.picture.style import PictureStyle
from swarmdeck.console.recording.codec import RecordedEvent
from swarmdeck.console.recording.reader import Recording
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.core.bounds import Bounds
from swarmdeck.core.constants import ROBOT_RADIUS
from swarmdeck.core.errors import SwarmdeckError

#: H.264 encoders tried in this order (PyAV's wheels carry libx264).
H264_ENCODERS = ("libx264", "libopenh264", "h264")
_SHIFT = 4  # OpenCV fixed-point bits for sub-pixel drawing
_ONE = 1 << _SHIFT

BACKGROUND = (246, 246, 242)
BAND = (32, 34, 40)
GRID = np.array([150, 150, 150], dtype=float)
RING = tuple(int(c) for c in CHANGED)  # the ring round a robot the barrier changed
ESTOP = tuple(int(c) for c in STOPPED)


class VideoExportError(SwarmdeckError):
    """The video cannot be made: no H.264 encoder, a recording without frames, bad settings."""


@dataclass(frozen=True)
class VideoStyle:
    """What the video looks like.

    width, height: pixels (even: yuv420p halves the chroma). fps: video frames per s of recording
    time. robot_radius: m. events_shown: s an event stays in the footer. camera_panel: width of the
    camera picture's panel as a fraction of the video width (only when the recording has pictures). crf: x264 quality (18 near lossless … 28 small files);
    preset: x264 speed (superfast: ~2× the speed of veryfast for ~2× the bytes).
    """

    width: int = 1280
    height: int = 720
    fps: float = 30.0
    robot_radius: float = ROBOT_RADIUS
    events_shown: float = 3.0
    camera_panel: float = 0.3
    crf: int = 23
    preset: str = "superfast"

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            v = getattr(self, name)
            if not (isinstance(v, int) and 64 <= v <= 4096 and v % 2 == 0):
                raise VideoExportError(f"video {name} must be an even number of pixels in [64, 4096], got {v!r}")
        if not (isinstance(self.fps, (int, float)) and math.isfinite(self.fps) and 0 < self.fps <= 120):
            raise VideoExportError(f"video fps must be in (0, 120], got {self.fps!r}")


@dataclass(frozen=True)
class VideoLayout:
    """Where the arena is in the video: ``scale`` px per m, arena rectangle ``(left, top, w, h)`` px,
    header and footer band height px, camera panel ``(left, top, w, h)`` px (w = 0: none). Arena x grows
    right, y up; pixel rows grow down."""

    bounds: Bounds
    width: int
    height: int
    scale: float
    left: int
    top: int
    arena_w: int
    arena_h: int
    band: int
    panel: tuple[int, int, int, int] = (0, 0, 0, 0)

    @classmethod
    def fit(cls, bounds: Bounds, width: int, height: int, panel: float = 0.0) -> VideoLayout:
        """The arena as large as fits between a header and a footer band, centred, aspect kept; with
        ``panel`` > 0 that fraction of the width (right) is kept for the camera picture."""
        area = Bounds(*(float(b) for b in bounds))
        band = max(18, round(0.055 * height))
        margin = max(4, round(0.012 * height))
        pw = int(panel * width)
        avail_w, avail_h = width - pw - 2 * margin, height - 2 * band - 2 * margin
        scale = min(avail_w / area.width, avail_h / area.height)
        aw, ah = max(2, int(scale * area.width)), max(2, int(scale * area.height))
        top = band + (height - 2 * band - ah) // 2
        box = (width - pw, top, pw - margin, ah) if pw else (0, 0, 0, 0)
        return cls(area, width, height, scale, (width - pw - aw) // 2, top, aw, ah, band, box)

    def to_px(self, xy: NDArray[np.float64]) -> NDArray[np.float64]:
        """(…, 2) arena points, m → (…, 2) pixel coordinates (column, row), float."""
        xy = np.asarray(xy, dtype=float)
        x0, _, _, y1 = self.bounds
        out = np.empty_like(xy)
        out[..., 0] = self.left + (xy[..., 0] - x0) * self.scale
        out[..., 1] = self.top + (y1 - xy[..., 1]) * self.scale
        return out

    def fixed(self, xy: NDArray[np.float64]) -> NDArray[np.int32]:
        """:meth:`to_px` in OpenCV's fixed point (``shift`` = 4), int32, for sub-pixel drawing."""
        return np.round(self.to_px(xy) * _ONE).astype(np.int32)


def video_frame_count(duration: float, fps: float) -> int:
    """Video frames for ``duration`` s of recording at ``fps``: one at 0 and one every 1/fps s up to the end."""
    return int(math.floor(max(duration, 0.0) * fps + 1e-6)) + 1


# ---------------------------------------------------------------------------- drawing
class FrameRenderer:
    """Draws Frames into RGB images (height, width, 3) uint8 for one layout. Keeps only caches that
    depend on the layout, the robot ids and the camera picture."""

    def __init__(self, layout: VideoLayout, style: VideoStyle, picture: PictureStyle | None = None) -> None:
        import cv2

        self.cv2 = cv2
        self.layout = layout
        self.style = style
        self.picture_style = picture or PictureStyle()
        lay = layout
        self.font_scale = max(0.35, lay.height / 720 * 0.6)
        self.thick = max(1, round(lay.height / 720 * 1.5))
        x0, x1, y0, y1 = lay.bounds
        # heat map sampled coarsely (as the console does) and stretched to the arena rectangle
        self.heat_px_per_m = self.picture_style.heatmap_px(lay.bounds)
        self.empty_heat = np.empty((lay.arena_h, lay.arena_w, 3), dtype=np.uint8)
        self.empty_heat[:] = LUT[0]
        self.grid_mask = self._grid_mask(0.5)
        r = style.robot_radius
        self.body = robot_outline(r)  # the picture's teardrop, nose at +x
        self.tick = np.array([[0.25 * r, 0.0], [1.35 * r, 0.0]])
        ring = np.linspace(0.0, 2 * np.pi, 17)[:-1]
        self.unit_ring = np.column_stack((np.cos(ring), np.sin(ring)))
        self.base = np.empty((lay.height, lay.width, 3), dtype=np.uint8)  # background, bands, arena outline
        self.base[:] = BACKGROUND
        self.base[:lay.band] = BAND
        self.base[lay.height - lay.band:] = BAND
        cv2.rectangle(self.base, (lay.left - 2, lay.top - 2), (lay.left + lay.arena_w + 1, lay.top + lay.arena_h + 1),
                      BOUNDARY, 2)
        self._labels_key: tuple[int, ...] | None = None
        self._labels: tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]] | None = None
        self._picture: NDArray[np.uint8] | None = None
        self._floor: NDArray[np.uint8] = self.empty_heat
        self._floor_of: Frame | None = None

    def _grid_mask(self, step: float) -> NDArray[np.bool_]:
        lay = self.layout
        x0, x1, y0, y1 = lay.bounds
        mask = np.zeros((lay.arena_h, lay.arena_w), dtype=bool)
        xs = np.arange(math.ceil(x0 / step) * step, x1 + 1e-9, step)
        ys = np.arange(math.ceil(y0 / step) * step, y1 + 1e-9, step)
        cols = np.clip(np.round((xs - x0) * lay.scale).astype(int), 0, lay.arena_w - 1)
        rows = np.clip(np.round((y1 - ys) * lay.scale).astype(int), 0, lay.arena_h - 1)
        mask[:, cols] = True
        mask[rows, :] = True
        return mask

    # ------------------------------------------------------------------ camera
    def set_camera(self, jpeg: bytes | None) -> None:
        """The camera picture (JPEG/PNG bytes) for the panel from now on; undecodable bytes keep the old one."""
        if jpeg is None:
            return
        cv2 = self.cv2
        img = cv2.imdecode(np.frombuffer(jpeg, dtype=np.uint8), cv2.IMREAD_COLOR)
        if img is None or img.ndim != 3:
            return
        _, _, pw, ph = self.layout.panel
        if pw < 8 or ph < 8:
            return
        k = min(pw / img.shape[1], ph / img.shape[0])
        w, h = max(4, int(k * img.shape[1])), max(4, int(k * img.shape[0]))
        self._picture = cv2.cvtColor(cv2.resize(img, (w, h), interpolation=cv2.INTER_AREA), cv2.COLOR_BGR2RGB)

    # ------------------------------------------------------------------ one image
    def render(self, frame: Frame, t: float, events: Sequence[RecordedEvent] = ()) -> NDArray[np.uint8]:
        """The picture of ``frame`` at recording time ``t`` s, with ``events`` (the recent ones) in the footer."""
        cv2, lay = self.cv2, self.layout
        pic = picture_of(frame, self.picture_style)
        img = self.base.copy()
        top, left, ah, aw = lay.top, lay.left, lay.arena_h, lay.arena_w
        arena = img[top:top + ah, left:left + aw]
        if frame is not self._floor_of:  # a video frame repeating a recorded Frame reuses its floor
            floor = self.empty_heat.copy() if frame.density is None else cv2.resize(
                heatmap(frame.density, lay.bounds, self.heat_px_per_m), (aw, ah), interpolation=cv2.INTER_LINEAR)
            floor[self.grid_mask] = (0.7 * floor[self.grid_mask] + 0.3 * GRID).astype(np.uint8)
            self._floor, self._floor_of = floor, frame
        arena[:] = self._floor
        aa, sh = cv2.LINE_AA, _SHIFT
        if len(pic.edges):
            cv2.polylines(img, list(lay.fixed(pic.edges)), False, VORONOI, 1, aa, sh)  # thick AA lines cost 4×
        if len(pic.centroids):
            d = 0.018 * np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
            cv2.fillPoly(img, list(lay.fixed(pic.centroids[:, None, :] + d[None])), CENTROID, aa, sh)
        pts = pic.points
        if pic.glyphs and pic.n:
            discs = pts[:, None, :] + pic.ring_radius * self.unit_ring[None]
            cv2.polylines(img, list(lay.fixed(discs)), True, SAFETY_RING, 1, aa, sh)
        if len(pic.pairs):
            self._pairs(img, pts, pic.pairs, pic.pair_h)
        if pic.changed.any():
            rings = pic.poses[pic.changed, None, :2] + CHANGED_RING * self.style.robot_radius * self.unit_ring[None]
            cv2.polylines(img, list(lay.fixed(rings)), True, RING, max(1, self.thick), aa, sh)
        c = pic.contacts
        if len(c):
            dots = c[:, None, :] + 0.03 * self.unit_ring[None]
            cv2.fillPoly(img, list(lay.fixed(dots)), CONTACT, aa, sh)
        if pic.sensors is not None and len(pic.sensors.ray_starts):
            self._rays(img, pic)
        if pic.n:
            self._robots(img, frame, pic)
            if pic.sensors is not None and pic.sensors.leds is not None:
                self._leds(img, pic)
        if frame.run_state == "estop":
            cv2.rectangle(img, (left - 3, top - 3), (left + aw + 2, top + ah + 2), ESTOP, 6)
        if self._picture is not None:
            self._draw_camera(img)
        self._header(img, frame, t)
        self._footer(img, t, events)
        return img

    def _pairs(self, img: NDArray[np.uint8], pts: NDArray[np.float64], pairs: NDArray[np.int64],
               h: NDArray[np.float64]) -> None:
        """Active barrier pairs, one ``polylines`` call per colour (h quantised to 6 levels of the picture's ramp)."""
        h_full = self.picture_style.h_full
        level = np.round(np.clip(np.asarray(h, dtype=float) / h_full, 0.0, 1.0) * 5) / 5
        cols = pair_colors(level * h_full, h_full)
        segs = self.layout.fixed(np.stack((pts[pairs[:, 0]], pts[pairs[:, 1]]), axis=1))
        keys = level * 5
        for k in np.unique(keys):
            sel = keys == k
            col = tuple(int(v) for v in cols[np.flatnonzero(sel)[0]])
            self.cv2.polylines(img, list(segs[sel]), False, col, 2 * self.thick + 1, self.cv2.LINE_AA, _SHIFT)

    def _rays(self, img: NDArray[np.uint8], pic: Picture) -> None:
        """The sensors' layer: ToF rays from sensor to end point and a dot at each end point."""
        layer = pic.sensors
        assert layer is not None
        segs = self.layout.fixed(np.stack((layer.ray_starts, layer.ray_ends), axis=1))
        self.cv2.polylines(img, list(segs), False, SENSOR_RAY, 1, self.cv2.LINE_AA, _SHIFT)
        dots = layer.ray_ends[:, None, :] + 0.012 * self.unit_ring[None]
        self.cv2.fillPoly(img, list(self.layout.fixed(dots)), SENSOR_HIT, self.cv2.LINE_AA, _SHIFT)

    def _leds(self, img: NDArray[np.uint8], pic: Picture) -> None:
        """Each lit LED as a small disc in its colour at the robot's centre, one ``fillPoly`` per colour."""
        layer = pic.sensors
        assert layer is not None and layer.leds is not None
        lit = np.flatnonzero(layer.led_on)
        if not len(lit):
            return
        dots = self.layout.fixed(pic.poses[lit, None, :2] + 0.45 * self.style.robot_radius * self.unit_ring[None])
        uniq, which = np.unique(layer.leds[lit], axis=0, return_inverse=True)
        which = np.asarray(which).reshape(-1)
        for k, col in enumerate(uniq):  # one call per distinct colour, not per robot
            self.cv2.fillPoly(img, list(dots[which == k]), tuple(int(v) for v in col), self.cv2.LINE_AA, _SHIFT)

    def _robots(self, img: NDArray[np.uint8], frame: Frame, pic: Picture) -> None:
        cv2, lay = self.cv2, self.layout
        poses = frame.poses
        c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
        rot = np.stack((np.stack((c, -s), -1), np.stack((s, c), -1)), axis=1)  # (N, 2, 2)
        bodies = poses[:, None, :2] + np.einsum("nij,vj->nvi", rot, self.body)
        ticks = poses[:, None, :2] + np.einsum("nij,vj->nvi", rot, self.tick)
        cols = pic.colors
        fixed = lay.fixed(bodies)
        uniq, which = np.unique(cols, axis=0, return_inverse=True)
        which = np.asarray(which).reshape(-1)
        for k, col in enumerate(uniq):  # a handful of state colours, not one call per robot
            cv2.fillPoly(img, list(fixed[which == k]), tuple(int(v) for v in col), cv2.LINE_AA, _SHIFT)
        cv2.polylines(img, list(lay.fixed(ticks)), False, HEADING, max(1, self.thick), cv2.LINE_AA, _SHIFT)
        if pic.virtual.any():  # as the console: the picture's dashed violet ring
            segs = np.stack(dashed_rings(poses[pic.virtual, :2], self.style.robot_radius), axis=1)
            cv2.polylines(img, list(lay.fixed(segs)), False, VIRTUAL_RING, max(1, self.thick), cv2.LINE_AA, _SHIFT)
        if pic.labelled:
            self._ids(img, frame)

    def _ids(self, img: NDArray[np.uint8], frame: Frame) -> None:
        """Robot ids above the robots: text masks rendered once per id set, placed all at once."""
        key = tuple(int(i) for i in frame.ids)
        if key != self._labels_key:
            self._labels_key, self._labels = key, self._label_masks(key)
        assert self._labels is not None
        robot, dy, dx = self._labels
        lay = self.layout
        anchor = lay.to_px(frame.poses[:, :2] + np.array([0.0, self.picture_style.label_offset + 0.02]))
        rows = np.round(anchor[robot, 1]).astype(np.intp) + dy
        cols = np.round(anchor[robot, 0]).astype(np.intp) + dx
        ok = (rows >= 0) & (rows < lay.height) & (cols >= 0) & (cols < lay.width)
        img[rows[ok], cols[ok]] = LABEL

    def _label_masks(self, ids: tuple[int, ...]) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]]:
        """(robot index, row offset, column offset) of every text pixel of every robot's id, centred."""
        cv2 = self.cv2
        fs, th = 0.8 * self.font_scale, max(1, self.thick)
        robot, dys, dxs = [], [], []
        masks: dict[int, tuple[NDArray[np.intp], NDArray[np.intp]]] = {}
        for k, rid in enumerate(ids):
            if rid not in masks:
                (w, h), base = cv2.getTextSize(str(rid), cv2.FONT_HERSHEY_SIMPLEX, fs, th)
                m = np.zeros((h + base + 2, w + 2), dtype=np.uint8)
                cv2.putText(m, str(rid), (1, h + 1), cv2.FONT_HERSHEY_SIMPLEX, fs, 255, th, cv2.LINE_8)
                yy, xx = np.nonzero(m)
                masks[rid] = (yy - (h + base + 2) // 2, xx - (w + 2) // 2)
            yy, xx = masks[rid]
            robot.append(np.full(len(yy), k, dtype=np.intp))
            dys.append(yy)
            dxs.append(xx)
        return np.concatenate(robot), np.concatenate(dys), np.concatenate(dxs)

    def _draw_camera(self, img: NDArray[np.uint8]) -> None:
        lay, inset = self.layout, self._picture
        assert inset is not None
        h, w = inset.shape[:2]
        left, top, pw, ph = lay.panel
        r0, c0 = top + (ph - h) // 2, left + (pw - w) // 2
        img[r0:r0 + h, c0:c0 + w] = inset

    def _text(self, img: NDArray[np.uint8], text: str, x: int, y: int, col: tuple[int, int, int],
              scale: float | None = None) -> int:
        cv2 = self.cv2
        fs = self.font_scale if scale is None else scale
        cv2.putText(img, text, (x, y), cv2.FONT_HERSHEY_SIMPLEX, fs, col, self.thick, cv2.LINE_AA)
        return cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, fs, self.thick)[0][0]

    def _header(self, img: NDArray[np.uint8], frame: Frame, t: float) -> None:
        lay = self.layout
        y = (lay.band + int(20 * self.font_scale)) // 2
        x = 10
        x += self._text(img, f"t {t:.2f} s", x, y, (255, 255, 255)) + 18
        b = frame.barrier
        parts = [f"{frame.n} robots", frame.behaviour]
        if b is not None:
            if not b.enabled:
                parts.append("barrier OFF")
            else:
                parts.append(f"barrier {b.n_active} active")
                if math.isfinite(b.min_distance):
                    parts.append(f"d_min {b.min_distance:.3f} m")
                if not b.ok:
                    parts.append(f"filter failed: {b.status}")
        x += self._text(img, "  |  ".join(parts), x, y, (200, 205, 215)) + 18
        if frame.run_state == "estop":
            (tw, th), _ = self.cv2.getTextSize("EMERGENCY STOP", self.cv2.FONT_HERSHEY_SIMPLEX, self.font_scale,
                                               self.thick)
            x = max(10, lay.width - tw - 16)  # over the end of the status text if the video is narrow
            self.cv2.rectangle(img, (x - 6, 2), (x + tw + 6, lay.band - 3), ESTOP, -1)
            self._text(img, "EMERGENCY STOP", x, y, (255, 255, 255))
        elif frame.run_state == "paused":
            self._text(img, "paused", max(x, lay.width - int(90 * self.font_scale / 0.6)), y, (170, 185, 210))

    def _footer(self, img: NDArray[np.uint8], t: float, events: Sequence[RecordedEvent]) -> None:
        lay = self.layout
        if not events:
            return
        text = "   ".join(f"{e.t:.1f} s {e.text}" for e in events[-3:])
        y = lay.height - (lay.band - int(20 * self.font_scale)) // 2 - 2
        self._text(img, text[:160], 10, y, (255, 215, 120), 0.85 * self.font_scale)


# ---------------------------------------------------------------------------- encoding
def _encoder(path: Path, style: VideoStyle) -> tuple[Any, Any]:
    """(container, stream) of an H.264/yuv420p MP4 at ``path``; VideoExportError naming what is missing."""
    try:
        import av
    except ImportError:
        raise VideoExportError("MP4 export needs PyAV (its wheels bundle FFmpeg with libx264): "
                               "pip install av") from None
    codec = None
    for name in H264_ENCODERS:
        try:
            av.codec.Codec(name, "w")
        except Exception:  # noqa: BLE001 - PyAV raises its own error types for unknown codecs
            continue
        codec = name
        break
    if codec is None:
        raise VideoExportError(f"this PyAV's FFmpeg has no H.264 encoder ({', '.join(H264_ENCODERS)}): "
                               "install the PyPI wheel, pip install --force-reinstall av")
    try:
        container = av.open(str(path), mode="w", format="mp4", options={"movflags": "+faststart"})
    except (OSError, av.FFmpegError) as exc:
        raise OSError(f"cannot write {path}: {exc}") from exc
    rate = Fraction(style.fps).limit_denominator(1001)
    stream = container.add_stream(codec, rate=rate)
    stream.width, stream.height, stream.pix_fmt = style.width, style.height, "yuv420p"
    if codec == "libx264":
        stream.options = {"crf": str(style.crf), "preset": style.preset}
    stream.codec_context.time_base = 1 / rate
    return container, stream


def export_video(recording: Recording, out: str | os.PathLike[str], style: VideoStyle | None = None,
                 start: float | None = None, end: float | None = None,
                 progress: Callable[[int, int], None] | None = None) -> tuple[Path, int]:
    """Write the recording's frames in [start, end] s as an MP4 to ``out``; returns (path, video frames).

    ``progress(done, total)`` is called after every video frame. Raises :class:`VideoExportError`
    (no frames, no encoder) or OSError (cannot write ``out``).
    """
    style = style or VideoStyle()
    first = recording.first_frame
    if first is None:
        raise VideoExportError(f"{recording.path} holds no readable frame")
    t0 = 0.0 if start is None else max(0.0, float(start))
    t1 = recording.duration if end is None else min(float(end), recording.duration)
    if not t1 >= t0:
        raise VideoExportError(f"nothing to export between {t0} s and {t1} s (the recording lasts "
                               f"{recording.duration:.3f} s)")
    total = video_frame_count(t1 - t0, style.fps)
    cameras = recording.camera_pictures(max(0.0, t0 - 60.0), t1 + 1e-6)
    pending = next(cameras, None)
    layout = VideoLayout.fit(first.bounds, style.width, style.height,
                             style.camera_panel if pending is not None else 0.0)
    renderer = FrameRenderer(layout, style)
    events = sorted(recording.events(None, t1 + 1e-6), key=lambda e: e.t)
    event_t = [e.t for e in events]

    path = Path(out)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.part")
    container, stream = _encoder(tmp, style)
    import av
    import cv2

    done = 0
    try:
        cur: tuple[float, Frame] | None = recording.frame_at(t0)
        frames = recording.frames(t0 + 1e-9, t1 + 1e-6)
        upcoming = next(frames, None)
        while done < total:
            t = t0 + done / style.fps
            while upcoming is not None and upcoming[0] <= t + 1e-9:
                cur, upcoming = upcoming, next(frames, None)
            while pending is not None and pending[0] <= t + 1e-9:
                renderer.set_camera(pending[1])
                pending = next(cameras, None)
            assert cur is not None
            recent = events[bisect_left(event_t, t - style.events_shown):bisect_right(event_t, t + 1e-9)]
            image = renderer.render(cur[1], t, recent)
            # OpenCV's RGB → I420 (BT.601, limited range, as FFmpeg's default) is ~15× faster than swscale here
            vf = av.VideoFrame.from_ndarray(cv2.cvtColor(image, cv2.COLOR_RGB2YUV_I420), format="yuv420p")
            vf.pts = done
            for packet in stream.encode(vf):
                container.mux(packet)
            done += 1
            if progress is not None:
                progress(done, total)
        for packet in stream.encode(None):
            container.mux(packet)
        container.close()
        os.replace(tmp, path)
    except BaseException:
        try:
            container.close()
        except Exception:  # noqa: BLE001 - already failing; the original error is the one to report
            pass
        tmp.unlink(missing_ok=True)
        raise
    return path, done
