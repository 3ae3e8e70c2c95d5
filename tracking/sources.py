"""Camera sources behind one interface, newest frame only.

Every source has ``read(now) -> CameraFrame | None`` (the newest frame not handed out before,
or None when there is none), ``status`` (one line), ``ok`` and ``close()``. Opening failures and
read failures become ``status`` text, never exceptions into the loop. Images are RGB uint8.

* :class:`OpenCVCamera` — webcam index or stream URL via ``cv2.VideoCapture``, grabbed in a
  background thread that keeps only the newest frame (stamped at capture on the loop's clock).
* :class:`VideoFileSource` — a video file, looped; paced at its frame rate (skipping frames to
  stay current) or one frame per read (as fast as possible).
* :class:`ImageFolderSource` — the images of a folder in name order, same pacing options.
* :class:`~swarmdeck.tracking.synthetic.SyntheticCamera` — renders the simulated arena.
"""
from __future__ import annotations

import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import cv2
import numpy as np

from swarmdeck.core.errors import SwarmdeckError
from swarmdeck.core.service_thread import ServiceThread
from swarmdeck.tracking.imageread import IMAGE_SUFFIXES, ImageReadError, decoded_to_rgb, read_image
from swarmdeck.tracking.types import CameraFrame


class CameraError(ValueError, SwarmdeckError):
    """A camera specification that cannot name any source (e.g. a path that does not exist)."""


@runtime_checkable
class CameraSource(Protocol):
    """What the tracker reads frames from."""

    status: str

    @property
    def ok(self) -> bool: ...

    def read(self, now: float) -> CameraFrame | None: ...

    def close(self) -> None: ...


class OpenCVCamera:
    """A webcam (int index) or network stream (URL) read in a background thread.

    The thread grabs continuously and keeps only the newest frame, stamped with ``clock()`` at
    capture; ``read`` returns it once. When the device fails the thread reopens it every
    ``retry_s`` seconds and ``status`` says so.
    """

    def __init__(self, device: int | str, width: int | None = None, height: int | None = None,
                 fps: float | None = None, clock: Callable[[], float] = time.monotonic,
                 retry_s: float = 2.0) -> None:
        self.device = device
        self._size = (width, height)
        self._fps = fps
        self._clock = clock
        self._retry_s = retry_s
        self._lock = threading.Lock()
        self._newest: CameraFrame | None = None
        self._handed = -1
        self._index = 0
        self.status = f"camera {device}: opening"
        self.frames_grabbed = 0
        self.failures = 0
        self._service = ServiceThread(self._run, f"camera-{device}")
        self._service.start()

    @property
    def ok(self) -> bool:
        """True while frames are arriving."""
        return self.status.endswith("streaming")

    def _open(self) -> cv2.VideoCapture | None:
        cap = cv2.VideoCapture(self.device)
        if not cap.isOpened():
            cap.release()
            return None
        w, h = self._size
        if w:
            cap.set(cv2.CAP_PROP_FRAME_WIDTH, w)
        if h:
            cap.set(cv2.CAP_PROP_FRAME_HEIGHT, h)
        if self._fps:
            cap.set(cv2.CAP_PROP_FPS, self._fps)
        cap.set(cv2.CAP_PROP_BUFFERSIZE, 1)
        return cap

    def _run(self) -> None:
        cap = None
        svc = self._service
        while not svc.stopping:
            if cap is None:
                cap = self._open()
                if cap is None:
                    self.failures += 1
                    self.status = f"camera {self.device}: cannot open (retrying every {self._retry_s:g} s)"
                    svc.wait(self._retry_s)
                    continue
            ok, img = cap.read()
            stamp = self._clock()
            wall = time.monotonic()
            rgb = decoded_to_rgb(img) if ok else None
            if rgb is None:
                self.failures += 1
                self.status = f"camera {self.device}: read failed, reopening"
                cap.release()
                cap = None
                svc.wait(min(self._retry_s, 0.5))
                continue
            with self._lock:
                self._newest = CameraFrame(rgb, stamp, self._index, wall)
                self._index += 1
            self.frames_grabbed += 1
            self.status = f"camera {self.device}: {rgb.shape[1]}×{rgb.shape[0]} streaming"
        if cap is not None:
            cap.release()

    def read(self, now: float) -> CameraFrame | None:
        """The newest grabbed frame, once (None when no new frame arrived since the last read)."""
        with self._lock:
            f = self._newest
        if f is None or f.index == self._handed:
            return None
        self._handed = f.index
        return f

    def close(self) -> None:
        """Stop the thread and release the device."""
        self._service.stop()
        self.status = f"camera {self.device}: closed"


class _PacedFrames:
    """Which frame index a paced or free-running source should show at ``now``."""

    def __init__(self, fps: float, paced: bool) -> None:
        self.fps = fps
        self.paced = paced
        self.t0: float | None = None
        self.next = 0

    def index(self, now: float) -> int:
        if not self.paced:
            i = self.next
            self.next += 1
            return i
        if self.t0 is None:
            self.t0 = now
        return int(np.floor((now - self.t0) * self.fps + 1e-9))


class VideoFileSource:
    """A video file, looped. ``paced``: frames follow the file's rate (``fps`` overrides it) on
    the loop's clock and stale frames are skipped (grabbed, not decoded); otherwise each read
    returns the next frame. Frames are stamped ``now``."""

    def __init__(self, path: str | Path, paced: bool = True, loop: bool = True, fps: float | None = None) -> None:
        self.path = Path(path)
        self.loop = loop
        self._cap: cv2.VideoCapture | None = None
        self._pos = 0            # index of the next frame the capture will return
        self._last = -1
        self._n = 0
        self._pacer = _PacedFrames(fps or 30.0, paced)
        self.status = f"video {self.path.name}: opening"
        if not self.path.is_file():
            self.status = f"video {self.path}: no such file"
            return
        cap = cv2.VideoCapture(str(self.path))
        if not cap.isOpened():
            self.status = f"video {self.path}: cannot open (not a video OpenCV can read)"
            cap.release()
            return
        self._cap = cap
        self._n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
        file_fps = cap.get(cv2.CAP_PROP_FPS)
        if fps is None and file_fps and np.isfinite(file_fps) and file_fps > 0:
            self._pacer.fps = float(file_fps)
        self.status = f"video {self.path.name}: {self._n} frames at {self._pacer.fps:g} fps"

    @property
    def ok(self) -> bool:
        """True while the file can be read."""
        return self._cap is not None

    def _rewind(self) -> None:
        assert self._cap is not None
        self._cap.set(cv2.CAP_PROP_POS_FRAMES, 0)
        self._pos = 0

    def read(self, now: float) -> CameraFrame | None:
        """The frame due at ``now`` (None if it was already returned, or on error/end)."""
        if self._cap is None:
            return None
        want = self._pacer.index(now)
        if self._n > 0 and self.loop:
            want_in = want % self._n
        else:
            want_in = want
        if want == self._last:
            return None
        if want_in < self._pos:
            self._rewind()
        while self._pos < want_in:                      # skip stale frames without decoding
            if not self._cap.grab():
                break
            self._pos += 1
        ok, img = self._cap.read()
        if not ok:
            if not self.loop:
                self.status = f"video {self.path.name}: end of file"
                return None
            self._rewind()
            ok, img = self._cap.read()
            if not ok:
                self.status = f"video {self.path.name}: cannot decode frames"
                self._cap.release()
                self._cap = None
                return None
        self._pos += 1
        self._last = want
        rgb = decoded_to_rgb(img)
        if rgb is None:
            self.status = f"video {self.path.name}: unsupported frame format"
            return None
        return CameraFrame(rgb, float(now), want, time.monotonic())

    def close(self) -> None:
        """Release the file."""
        if self._cap is not None:
            self._cap.release()
            self._cap = None
        self.status = f"video {self.path.name}: closed"


class ImageFolderSource:
    """The images of a folder in name order, looped; paced at ``fps`` or one per read.
    Images are read by :func:`~swarmdeck.tracking.imageread.read_image` (any depth, EXIF
    orientation applied), as ``swarmdeck calibrate`` reads them. Unreadable images are
    skipped with a status message and counted."""

    def __init__(self, folder: str | Path, paced: bool = False, fps: float = 30.0, loop: bool = True) -> None:
        self.folder = Path(folder)
        self.loop = loop
        self.unreadable = 0
        self._pacer = _PacedFrames(fps, paced)
        self._last = -1
        self.files: list[Path] = []
        if not self.folder.is_dir():
            self.status = f"image folder {self.folder}: no such folder"
            return
        self.files = sorted(p for p in self.folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
        self.status = (f"image folder {self.folder.name}: {len(self.files)} images" if self.files
                       else f"image folder {self.folder}: no images ({', '.join(IMAGE_SUFFIXES)})")

    @property
    def ok(self) -> bool:
        """True when there are images to show."""
        return bool(self.files)

    def read(self, now: float) -> CameraFrame | None:
        """The image due at ``now`` (None if already returned, past the end, or unreadable)."""
        if not self.files:
            return None
        want = self._pacer.index(now)
        if want == self._last:
            return None
        self._last = want
        if want >= len(self.files) and not self.loop:
            self.status = f"image folder {self.folder.name}: end"
            return None
        path = self.files[want % len(self.files)]
        try:
            rgb = read_image(path)
        except ImageReadError as exc:
            self.unreadable += 1
            self.status = (f"image folder {self.folder.name}: cannot read {path.name}: {exc} "
                           f"({self.unreadable} unreadable)")
            return None
        return CameraFrame(rgb, float(now), want, time.monotonic())

    def close(self) -> None:
        """Nothing to release."""
        self.status = f"image folder {self.folder.name}: closed"


def check_device(index: int) -> None:
    """:class:`CameraError` unless webcam ``index`` opens now (OpenCV's own warnings silenced).

    :class:`OpenCVCamera` keeps retrying a camera that fails during a run; a camera that is not
    there at start is a mistake in the command line, said in one line.
    """
    level = cv2.utils.logging.getLogLevel()
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)
    try:
        cap = cv2.VideoCapture(index)
        opened = cap.isOpened()
        cap.release()
    finally:
        cv2.utils.logging.setLogLevel(level)
    if not opened:
        raise CameraError(f"camera {index}: no camera with that index can be opened (is it connected, "
                          f"is /dev/video{index} readable, is another program using it?)")


def open_source(spec: str | int, *, paced: bool = True, get_poses: Callable[[float], np.ndarray] | None = None,
                ids: list[int] | None = None, size: tuple[int, int] | None = None,
                **synthetic_kw: Any) -> CameraSource:
    """A source from a command-line style spec.

    ``"synthetic"`` → :class:`SyntheticCamera` (needs ``get_poses``); an int or digit string →
    webcam index; ``scheme://…`` → stream URL; a folder → :class:`ImageFolderSource`; a file →
    :class:`VideoFileSource`. ``size`` (w, h) is requested from webcams and streams. Raises
    :class:`CameraError` when the spec names nothing (missing path, synthetic without
    ``get_poses``).
    """
    from swarmdeck.tracking.synthetic import SyntheticCamera, SyntheticCameraConfig

    w, h = size if size is not None else (None, None)
    if isinstance(spec, int) or (isinstance(spec, str) and spec.strip().isdigit()):
        check_device(int(spec))
        return OpenCVCamera(int(spec), width=w, height=h)
    s = str(spec).strip()
    if s == "synthetic":
        if get_poses is None:
            raise CameraError("the synthetic camera needs get_poses (a callable now -> (N, 3) poses)")
        return SyntheticCamera(get_poses, ids=ids, config=SyntheticCameraConfig(**synthetic_kw))
    if "://" in s:
        return OpenCVCamera(s, width=w, height=h)
    p = Path(s).expanduser()
    if p.is_dir():
        return ImageFolderSource(p, paced=paced)
    if p.is_file():
        return VideoFileSource(p, paced=paced)
    raise CameraError(f"camera {s!r} is not 'synthetic', a webcam index, a stream URL, a folder of images "
                      f"or a video file")
