"""A camera and a tracker combined: one call per control tick gives robot poses.

``CameraPoseSource.read(now) -> TrackedPoses`` gives the tracker's full record (stamps,
staleness, duplicates, homography state); ``health()`` the status-line numbers;
``rectified_image()`` the arena-aligned top-down picture for drawing as the floor;
``thumbnail()`` the raw view. :class:`TrackedPoseSource` is the same camera as the control
loop's :class:`~swarmdeck.core.ports.PoseSource` (``read(now) -> SensedPoses`` for the robots
the loop controls), which the console loop reads in place of the simulator's truth.
"""
from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import cv2
import numpy as np

from swarmdeck.core.bounds import Bounds
from swarmdeck.core.ports import Closeable, SensedPoses
from swarmdeck.tracking.calibration import CameraCalibration
from swarmdeck.tracking.config import TrackerConfig
from swarmdeck.tracking.homography import apply_homography
from swarmdeck.tracking.sources import CameraError, CameraSource, open_source
from swarmdeck.tracking.synthetic import SyntheticCamera, SyntheticCameraConfig
from swarmdeck.tracking.tracker import Tracker
from swarmdeck.tracking.types import CameraFrame, TrackedPoses


class CameraPoseSource:
    """Reads the newest frame of ``source`` and tracks it.

    ``clock`` (wall time) measures frame rate and processing time; latency is capture →
    poses ready, from ``CameraFrame.wall`` (``time.monotonic``) to the end of tracking.
    ``rectify_height`` (m above the reference plane; default: the tag height, so tags line up
    with robots drawn in metres) and ``px_per_m`` set the rectified image.
    """

    def __init__(self, source: CameraSource, tracker: Tracker | None = None,
                 clock: Callable[[], float] = time.monotonic, px_per_m: float = 200.0,
                 rectify_height: float | None = None, thumbnail_width: int = 320) -> None:
        self.source = source
        self.tracker = tracker if tracker is not None else Tracker()
        self._clock = clock
        self.px_per_m = px_per_m
        cfg = self.tracker.config
        self.rectify_height = (cfg.tag_height - cfg.reference_height) if rectify_height is None else rectify_height
        self.thumbnail_width = thumbnail_width
        self.frame: CameraFrame | None = None
        self.poses: TrackedPoses = self.tracker.last
        self._fps = float("nan")
        self._last_frame_wall: float | None = None
        self._latency = float("nan")
        self._processing = float("nan")
        self._frames = 0
        self._no_frame_ticks = 0
        self._source_error = ""
        self._rect_cache: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self._rect_img: tuple[int, np.ndarray] | None = None

    @classmethod
    def open(cls, spec: str | int, *, get_poses: Callable[[float], np.ndarray] | None = None,
             ids: Sequence[int] | None = None, config: TrackerConfig | str | Path | None = None,
             get_density: Callable[[float], np.ndarray | None] | None = None,
             synthetic: SyntheticCameraConfig | None = None, paced: bool = True) -> CameraPoseSource:
        """Build a camera + tracker from a command-line spec (``swarmdeck console --camera``).

        ``"synthetic"``: a :class:`SyntheticCamera` rendering ``get_poses(now)`` (robot ``ids``)
        and ``get_density(now)``; its tracker uses the camera's layout, tag height and exact
        intrinsics, or ``config`` (completed with the exact intrinsics when it has none). Otherwise (webcam index, URL, video file, image folder) the
        tracker config comes from ``config`` (a :class:`TrackerConfig` or the JSON file written
        by ``swarmdeck calibrate arena``) or the defaults; webcams are asked for the calibrated
        image size. ``ids`` become ``expected_ids`` so a
        robot that never shows up is reported stale. Raises :class:`CameraError` /
        ``ConfigError`` for a spec or file that names nothing usable.
        """
        cfg = TrackerConfig.load(config) if isinstance(config, (str, Path)) else config
        if str(spec).strip() == "synthetic":
            if get_poses is None:
                raise CameraError("the synthetic camera needs get_poses (a callable now -> (N, 3) poses)")
            cam = SyntheticCamera(get_poses, ids=ids, config=synthetic or SyntheticCameraConfig(),
                                  get_density=get_density)
            exact = CameraCalibration.from_camera(cam.renderer.camera)
            if cfg is None:
                sc = cam.config
                cfg = TrackerConfig(dictionary=sc.dictionary, references=sc.references, tag_size=sc.tag_size,
                                    tag_height=sc.tag_height, bounds=sc.bounds, calibration=exact)
            elif cfg.calibration is None:
                cfg = cfg.with_(calibration=exact)
            source: CameraSource = cam
        else:
            cfg = cfg if cfg is not None else TrackerConfig()
            source = open_source(spec, paced=paced,
                                 size=None if cfg.calibration is None else cfg.calibration.image_size)
        if ids is not None:
            cfg = cfg.with_(expected_ids=tuple(sorted(set(cfg.expected_ids) | {int(i) for i in ids})))
        return cls(source, Tracker(cfg))

    def close(self) -> None:
        """Close the camera source."""
        self.source.close()

    def read(self, now: float) -> TrackedPoses:
        """Newest frame → poses; without a new frame the previous poses with ``seen`` False
        and staleness judged at ``now``. Never raises."""
        wall0 = self._clock()
        try:
            frame = self.source.read(now)
            self._source_error = ""
        except Exception as exc:  # noqa: BLE001 - a broken source must not stop the loop
            frame = None
            self._source_error = f"camera error: {type(exc).__name__}: {exc}"
        if frame is None:
            self._no_frame_ticks += 1
            why = self._source_error or self.source.status
            self.poses = self.tracker.poses_at(now, f"no new frame ({why}); {self.tracker.last.status}")
            return self.poses
        wall0 = self._clock()
        tp = self.tracker.update(frame)
        wall1 = self._clock()
        self._processing = wall1 - wall0
        # latency: capture (frame.wall, time.monotonic) → poses ready
        lat = time.monotonic() - frame.wall
        self._latency = lat if math.isfinite(lat) and lat >= 0.0 else self._processing
        if self._last_frame_wall is not None:
            dt = wall1 - self._last_frame_wall
            if dt > 0:
                inst = 1.0 / dt
                self._fps = inst if not math.isfinite(self._fps) else 0.9 * self._fps + 0.1 * inst
        self._last_frame_wall = wall1
        self._frames += 1
        self.frame = frame
        if math.isfinite(now) and not math.isclose(now, frame.stamp):
            tp = dataclasses.replace(tp, stale=(now - tp.stamps) > self.tracker.config.stale_after_s)
        self.poses = tp
        return self.poses

    def health(self) -> dict:
        """JSON-able health for the status line: fps, latency_ms, processing_ms, frames,
        markers/references seen, homography state, source status."""
        h = self.tracker.health()
        def ms(x: float) -> float | None:
            return None if not math.isfinite(x) else round(1000.0 * x, 2)
        return {
            "fps": None if not math.isfinite(self._fps) else round(self._fps, 1),
            "latency_ms": ms(self._latency),
            "processing_ms": ms(self._processing),
            "frames": self._frames,
            "ticks_without_frame": self._no_frame_ticks,
            "source": self._source_error or self.source.status,
            "source_ok": bool(self.source.ok) and not self._source_error,
            "status": self.poses.status,
            **h,
        }

    def status_line(self) -> str:
        """One short line: 'camera 29.8 fps, 12 ms, 24 markers, refs 4/4, homography ok'."""
        h = self.health()
        fps = "–" if h["fps"] is None else f"{h['fps']:.1f}"
        lat = "–" if h["latency_ms"] is None else f"{h['latency_ms']:.0f} ms"
        return (f"camera {fps} fps, {lat}, {h['markers_seen']} markers, refs {h['references_seen']}/"
                f"{h['references_total']}, homography {h['homography']}")

    def thumbnail(self) -> np.ndarray | None:
        """The newest raw frame scaled to ``thumbnail_width`` px wide (RGB uint8), or None."""
        if self.frame is None:
            return None
        img = self.frame.image
        w = self.thumbnail_width
        h = max(1, int(round(img.shape[0] * w / img.shape[1])))
        return cv2.resize(img, (w, h), interpolation=cv2.INTER_AREA)

    def rectified_image(self) -> tuple[np.ndarray, tuple[float, float, float, float]] | None:
        """The newest frame warped to a top-down view of the arena bounds on the plane
        ``rectify_height`` m above the references: (image (h, w, 3) RGB uint8 with row 0 at
        y_max and column 0 at x_min, bounds). None without a frame or homography. Lens
        distortion is removed when the tracker has a calibration. In viser draw it with
        ``scene.add_image(..., render_width=x_max − x_min, render_height=y_max − y_min,
        position=(centre x, centre y, 0), wxyz=(0, 1, 0, 0))`` (REFERENCE.md §8: without that
        rotation it shows upside-down)."""
        H = self.tracker.homography
        if self.frame is None or H is None:
            return None
        bounds = self.tracker.config.bounds
        if self._rect_img is not None and self._rect_img[0] == self.frame.index:
            return self._rect_img[1], bounds
        mx, my = self._maps(H, bounds)
        img = cv2.remap(self.frame.image, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        self._rect_img = (self.frame.index, img)
        return img, bounds

    def _maps(self, H: np.ndarray, bounds: tuple[float, float, float, float]) -> tuple[np.ndarray, np.ndarray]:
        """Remap tables arena pixel → camera pixel, recomputed only when H moves the arena
        corners by more than 0.25 px."""
        x0, x1, y0, y1 = bounds
        Hinv = np.linalg.inv(H)
        probe = apply_homography(Hinv, np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], float))
        if self._rect_cache is not None and np.max(np.abs(self._rect_cache[0] - probe)) < 0.25:
            return self._rect_cache[1], self._rect_cache[2]
        w = max(2, int(round(Bounds.of(bounds).width * self.px_per_m)))
        h = max(2, int(round(Bounds.of(bounds).height * self.px_per_m)))
        xs = x0 + (np.arange(w) + 0.5) / self.px_per_m
        ys = y1 - (np.arange(h) + 0.5) / self.px_per_m
        X, Y = np.meshgrid(xs, ys)
        pts = np.stack([X, Y], axis=-1)
        C = self.tracker.camera_centre
        dh = self.rectify_height
        if C is not None and dh != 0.0:
            # a point at height dh seen along the ray from C meets the reference plane farther out
            pts = C[:2] + (pts - C[:2]) * (C[2] / (C[2] - dh))
        px = apply_homography(Hinv, pts)
        cal = self.tracker.config.calibration
        if cal is not None:
            px = cal.distort(px)
        mx, my = px[..., 0].astype(np.float32), px[..., 1].astype(np.float32)
        self._rect_cache = (probe, mx, my)
        return mx, my


class TrackedPoseSource:
    """The overhead camera as the control loop's :class:`~swarmdeck.core.ports.PoseSource`.

    Each ``read(now)`` tracks the newest frame of ``camera`` and gives one row per robot the
    loop controls: the last observed pose (zero before the first), ``seen`` when the tracker has
    a pose that is not stale (``TrackerConfig.stale_after_s``); stale or never-seen robots get
    zero commands and are fixed obstacles of the barrier.

    Args:
        camera: the camera and its tracker.
        ids: the robot ids the loop controls (the tracker lists them even before they are seen).
    """

    def __init__(self, camera: CameraPoseSource, ids: Sequence[int] | np.ndarray, name: str = "camera") -> None:
        self.camera = camera
        self.ids = np.asarray(ids, dtype=np.int64)
        self.name = name
        self._last = np.zeros((len(self.ids), 3))

    def read(self, now: float) -> SensedPoses:
        tp = self.camera.read(now)
        poses = np.array(self._last)
        seen = np.zeros(len(self.ids), dtype=bool)
        if len(tp.ids):
            pos = np.searchsorted(tp.ids, self.ids)
            pos_c = np.minimum(pos, len(tp.ids) - 1)
            hit = tp.ids[pos_c] == self.ids
            rows = pos_c[hit]
            got = tp.poses[rows]
            ok = np.all(np.isfinite(got), axis=1)
            stale = tp.stale[rows] if len(tp.stale) == len(tp.ids) else np.zeros(len(rows), dtype=bool)
            where = np.flatnonzero(hit)
            poses[where[ok]] = got[ok]
            seen[where] = ok & ~stale
        self._last = poses
        return SensedPoses(self.ids, poses, seen)

    def health(self) -> str:
        return self.camera.status_line()

    @property
    def image_ref(self) -> str | None:
        """Reference of the newest camera frame (for Frame.image_ref), or None before the first."""
        frame = self.camera.frame
        return None if frame is None else f"camera:{frame.index}"

    def image(self, ref: str) -> tuple[np.ndarray, tuple[float, float, float, float]] | None:
        """(rectified RGB image with row 0 at y_max, its bounds) of the newest frame, or None."""
        return self.camera.rectified_image()

    def close(self) -> None:
        if isinstance(self.camera.source, Closeable):
            self.camera.source.close()
