"""The overhead projector: its floor → projector homography, checked, fitted from a projected marker grid, saved.

Convention: ``H`` (3, 3) maps floor metres (x, y, 1) to projector pixels (u, v, 1) — u to the right, v down,
integer coordinates at pixel centres — normalised to ``H[2, 2] = 1``. The projector page draws the arena through
it (CSS ``matrix3d``); :func:`warp_to_projector` does the same in numpy for tests and the synthetic projector.

Calibration (``swarmdeck calibrate projector``): the projector shows :func:`marker_pattern` (an ArUco grid of a
dictionary the robots do not use), the overhead camera sees it, the camera's floor homography (undistorted px → m,
:mod:`~swarmdeck.tracking.homography`) puts the detected corners on the floor, and :func:`fit_projector` fits H
from (floor corners, pattern corners) with RANSAC and reports the reprojection error on the floor in mm.
:class:`SyntheticProjector` is a pinhole projector (pose, resolution) whose exact H the simulation tests check.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.bounds import Bounds
from swarmdeck.core.errors import SwarmdeckError
from swarmdeck.tracking.camera_model import PinholeCamera, overhead_camera
from swarmdeck.tracking.dictionaries import dictionary
from swarmdeck.tracking.homography import apply_homography
from swarmdeck.tracking.jsonfile import read_json_object, write_json

#: The pattern's dictionary: not the robots' DICT_4X4_50, so a robot on the floor is never taken for a marker.
PATTERN_DICTIONARY = "DICT_5X5_100"
#: Fewest markers a fit accepts (4 corners each; 4 markers spread the fit over the image).
MIN_MARKERS = 4
#: The arena must cover at least this fraction of itself on the projector's image.
MIN_ARENA_ON_IMAGE = 0.25


class ProjectorCalibrationError(ValueError, SwarmdeckError):
    """A projector calibration (file, homography or fit) that cannot be used; the message says why."""


def check_projector_homography(H: NDArray[np.float64] | object, bounds: Bounds | tuple[float, float, float, float],
                               size: tuple[int, int]) -> str | None:
    """Why ``H`` (floor m → projector px) cannot draw the arena ``bounds`` on a ``size`` (w, h) px image, or None.

    Refused: not a finite 3×3 matrix; singular (smallest / largest singular value < 1e-9); the projector's
    horizon crossing the arena (the arena would fold through infinity); less than :data:`MIN_ARENA_ON_IMAGE` of
    the arena (sampled on a 21 × 21 grid) landing on the image.
    """
    try:
        M = np.asarray(H, dtype=np.float64)
    except (TypeError, ValueError):
        return "the homography is not a 3×3 matrix of numbers"
    if M.shape != (3, 3):
        return f"the homography must be 3×3, got shape {M.shape}"
    if not np.all(np.isfinite(M)):
        return "the homography has non-finite entries"
    sv = np.linalg.svd(M, compute_uv=False)
    if not sv[0] > 0 or sv[2] / sv[0] < 1e-9:
        return "the homography is singular (it maps the floor onto a line or a point)"
    b = Bounds.of(bounds)
    s = np.linspace(0.0, 1.0, 21)
    X, Y = np.meshgrid(b.x_min + s * b.width, b.y_min + s * b.height)
    q = np.column_stack([X.ravel(), Y.ravel(), np.ones(X.size)]) @ M.T
    w = q[:, 2]
    if not (np.all(w > 0) or np.all(w < 0)):
        return "the projector's horizon crosses the arena (the homography folds the arena through infinity)"
    u, v = q[:, 0] / w, q[:, 1] / w
    W, Hh = size
    inside = float(np.mean((u >= -0.5) & (u <= W - 0.5) & (v >= -0.5) & (v <= Hh - 0.5)))
    if inside < MIN_ARENA_ON_IMAGE:
        return (f"the homography maps the arena off the projector image: {inside:.0%} of the arena lands on the "
                f"{W}×{Hh} px image (needs ≥ {MIN_ARENA_ON_IMAGE:.0%})")
    return None


@dataclass(frozen=True, eq=False)
class ProjectorCalibration:
    """A checked floor → projector homography. homography (3, 3) m → px; size (w, h) px of the projector's
    image; bounds the arena it was checked on; rms_mm the fit's reprojection error on the floor, mm;
    n_markers how many pattern markers the fit used."""

    homography: NDArray[np.float64]
    size: tuple[int, int]
    bounds: Bounds
    rms_mm: float = float("nan")
    n_markers: int = 0

    def __post_init__(self) -> None:
        w, h = self.size
        if not (isinstance(w, int) and isinstance(h, int) and w > 0 and h > 0):
            raise ProjectorCalibrationError(f"projector size must be two whole numbers of pixels > 0, got {self.size}")
        reason = check_projector_homography(self.homography, self.bounds, self.size)
        if reason is not None:
            raise ProjectorCalibrationError(reason)
        H = np.asarray(self.homography, dtype=np.float64)
        H = H / H[2, 2] if abs(H[2, 2]) > 1e-12 else H
        H.flags.writeable = False
        object.__setattr__(self, "homography", H)

    def to_dict(self) -> dict[str, object]:
        """The JSON form (file format of ``projector.json``)."""
        return {"homography": self.homography.tolist(), "size": list(self.size), "bounds": list(self.bounds),
                "rms_mm": None if not math.isfinite(self.rms_mm) else round(self.rms_mm, 3),
                "n_markers": int(self.n_markers)}

    @staticmethod
    def from_dict(d: dict[str, object]) -> ProjectorCalibration:
        """Parse and check the JSON form (:class:`ProjectorCalibrationError` naming what is wrong)."""
        try:
            H = np.asarray(d["homography"], dtype=np.float64)
            size_v = d["size"]
            bounds_v = d["bounds"]
            if not isinstance(size_v, (list, tuple)) or not isinstance(bounds_v, (list, tuple)):
                raise TypeError("size and bounds must be lists")
            size = (int(size_v[0]), int(size_v[1]))
            bx0, bx1, by0, by1 = (float(v) for v in bounds_v)
            bounds = Bounds(bx0, bx1, by0, by1)
            rms = d.get("rms_mm")
            n = d.get("n_markers", 0)
            return ProjectorCalibration(H, size, bounds, float(rms) if isinstance(rms, (int, float)) else float("nan"),
                                        int(n) if isinstance(n, int) else 0)
        except ProjectorCalibrationError:
            raise
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            raise ProjectorCalibrationError(f"projector calibration needs homography (3×3), size [w, h] and bounds "
                                            f"[x_min, x_max, y_min, y_max]: {exc}") from exc

    def save(self, path: str | Path) -> None:
        """Write the JSON file (:class:`ProjectorCalibrationError` if it cannot)."""
        write_json(path, self.to_dict(), "projector calibration", ProjectorCalibrationError)

    @staticmethod
    def load(path: str | Path) -> ProjectorCalibration:
        """Read and check the JSON file (:class:`ProjectorCalibrationError` naming the path and the problem)."""
        d = read_json_object(path, "projector calibration", ProjectorCalibrationError)
        try:
            return ProjectorCalibration.from_dict(d)
        except ProjectorCalibrationError as exc:
            raise ProjectorCalibrationError(f"{path}: {exc}") from None


@dataclass(frozen=True)
class SyntheticProjector:
    """A pinhole projector ``height_m`` m above the floor aimed at ``look_at`` with ``tilt`` rad from vertical
    (towards ``tilt_azimuth``: keystone) and ``roll`` rad, its ``width`` × ``height`` px image filling
    ``view_bounds`` (m) up to the margin — the same model as the synthetic camera, without lens distortion."""

    width: int = 1280
    height: int = 800
    height_m: float = 2.5
    tilt: float = 0.12
    tilt_azimuth: float = -math.pi / 2
    roll: float = 0.0
    look_at: tuple[float, float] = (0.0, 0.0)
    view_bounds: tuple[float, float, float, float] = (-1.75, 1.75, -1.1, 1.1)

    @property
    def size(self) -> tuple[int, int]:
        """(w, h) px."""
        return (self.width, self.height)

    def camera(self) -> PinholeCamera:
        """The projector as a pinhole camera (light runs the other way)."""
        return overhead_camera(self.size, self.height_m, self.tilt, self.tilt_azimuth, self.roll, self.look_at,
                               self.view_bounds, np.zeros(5), margin_px=0.0)

    def homography(self) -> NDArray[np.float64]:
        """The exact floor m → projector px homography (3, 3), H[2, 2] = 1."""
        cam = self.camera()
        H = cam.K @ cam.plane_homography(0.0)
        return np.asarray(H / H[2, 2], dtype=np.float64)


@dataclass(frozen=True, eq=False)
class MarkerPattern:
    """The calibration image: image (h, w) uint8 (black markers on white), ids (M,), corners_px (M, 4, 2) the
    markers' outer corners in projector pixels (OpenCV order TL, TR, BR, BL; pixel-centre coordinates)."""

    image: NDArray[np.uint8]
    ids: NDArray[np.int64]
    corners_px: NDArray[np.float64]
    dictionary: str = PATTERN_DICTIONARY


def marker_pattern(size: tuple[int, int], cols: int = 8, rows: int = 5, fill: float = 0.62,
                   dictionary_name: str = PATTERN_DICTIONARY) -> MarkerPattern:
    """A ``cols`` × ``rows`` grid of ArUco markers (ids 0…, row by row) over a ``size`` (w, h) px white image,
    each marker ``fill`` of its cell (the rest is the white quiet zone the detector needs)."""
    w, h = size
    d = dictionary(dictionary_name)
    n = cols * rows
    if n > d.bytesList.shape[0]:
        raise ProjectorCalibrationError(f"{cols}×{rows} markers do not fit {dictionary_name}")
    cw, ch = w / cols, h / rows
    side = int(math.floor(min(cw, ch) * fill))
    if side < 24:
        raise ProjectorCalibrationError(f"a {w}×{h} px projector gives {side} px markers in a {cols}×{rows} grid "
                                        "(needs ≥ 24 px): use fewer markers")
    img = np.full((h, w), 255, np.uint8)
    corners = np.zeros((n, 4, 2))
    for k in range(n):
        r, c = divmod(k, cols)
        x0 = int(round((c + 0.5) * cw - side / 2))
        y0 = int(round((r + 0.5) * ch - side / 2))
        img[y0:y0 + side, x0:x0 + side] = cv2.aruco.generateImageMarker(d, k, side, borderBits=1)
        e0, ex, ey = -0.5, x0 + side - 0.5, y0 + side - 0.5
        corners[k] = [[x0 + e0, y0 + e0], [ex, y0 + e0], [ex, ey], [x0 + e0, ey]]
    img.flags.writeable = False
    return MarkerPattern(img, np.arange(n, dtype=np.int64), corners, dictionary_name)


@dataclass(frozen=True, eq=False)
class ProjectorFit:
    """A fit: H (3, 3) floor m → projector px or None; ok; reason (why not, "" if ok); n_markers found;
    n_inliers corners the fit kept; rms_mm the kept corners' reprojection error on the floor, mm."""

    H: NDArray[np.float64] | None
    ok: bool
    reason: str
    n_markers: int
    n_inliers: int = 0
    rms_mm: float = float("nan")


def fit_projector(floor_corners: NDArray[np.float64], pattern_corners: NDArray[np.float64],
                  bounds: Bounds | tuple[float, float, float, float], size: tuple[int, int],
                  min_markers: int = MIN_MARKERS, ransac_px: float = 3.0) -> ProjectorFit:
    """Fit H from the found markers' corners on the floor (M, 4, 2) m and in the pattern (M, 4, 2) px.

    RANSAC (``ransac_px`` px) drops misdetected corners; the error reported is the RMS distance on the floor
    between each kept corner as the camera saw it and the pattern corner mapped back through H⁻¹, in mm.
    Refused (ok False, reason) with fewer than ``min_markers`` markers, a failed fit, or an H that
    :func:`check_projector_homography` refuses.
    """
    f = np.asarray(floor_corners, dtype=np.float64).reshape(-1, 4, 2)
    p = np.asarray(pattern_corners, dtype=np.float64).reshape(-1, 4, 2)
    m = len(f)
    if m < min_markers:
        return ProjectorFit(None, False, f"found {m} pattern marker(s), need {min_markers}", m)
    H, mask = cv2.findHomography(f.reshape(-1, 2), p.reshape(-1, 2), cv2.RANSAC, ransac_px)
    if H is None or mask is None or not np.all(np.isfinite(H)) or abs(H[2, 2]) < 1e-12:
        return ProjectorFit(None, False, f"the homography fit failed on {m} markers", m)
    H = H / H[2, 2]
    keep = mask.ravel().astype(bool)
    if keep.sum() < 4 * min_markers // 2:
        return ProjectorFit(None, False, f"only {int(keep.sum())} of {4 * m} corners agree on one homography", m,
                            int(keep.sum()))
    back = apply_homography(np.linalg.inv(H), p.reshape(-1, 2)[keep])
    rms = float(np.sqrt(np.mean(np.sum((back - f.reshape(-1, 2)[keep]) ** 2, axis=1)))) * 1000.0
    reason = check_projector_homography(H, bounds, size)
    if reason is not None:
        return ProjectorFit(None, False, reason, m, int(keep.sum()), rms)
    return ProjectorFit(np.asarray(H, dtype=np.float64), True, "", m, int(keep.sum()), rms)


def pixel_to_floor(bounds: Bounds | tuple[float, float, float, float], px_per_m: float) -> NDArray[np.float64]:
    """The 3×3 map from the pixels of a top-down arena image at ``px_per_m`` (row 0 at y_max, pixel centres at
    integers) to floor metres."""
    b = Bounds.of(bounds)
    s = 1.0 / px_per_m
    return np.array([[s, 0.0, b.x_min + 0.5 * s], [0.0, -s, b.y_max - 0.5 * s], [0.0, 0.0, 1.0]])


def warp_to_projector(arena_image: NDArray[np.uint8], bounds: Bounds | tuple[float, float, float, float],
                      H: NDArray[np.float64], size: tuple[int, int]) -> NDArray[np.uint8]:
    """The projector's image of a top-down ``arena_image`` (rows, cols[, 3]) covering ``bounds`` (row 0 at
    y_max): what the projector page shows, warped by H (floor m → projector px) onto a ``size`` (w, h) image,
    black outside the arena."""
    b = Bounds.of(bounds)
    rows, cols = arena_image.shape[:2]
    A = pixel_to_floor(b, cols / b.width)
    if abs(rows / b.height - cols / b.width) > 1e-6 * cols / b.width:
        A = np.array([[b.width / cols, 0.0, b.x_min + 0.5 * b.width / cols],
                      [0.0, -b.height / rows, b.y_max - 0.5 * b.height / rows], [0.0, 0.0, 1.0]])
    out = cv2.warpPerspective(np.ascontiguousarray(arena_image), np.asarray(H) @ A, size, flags=cv2.INTER_LINEAR,
                              borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    return np.asarray(out, dtype=np.uint8)


#: Adaptive-threshold windows (min, max, step) px for the pattern's markers (≈ 40–80 camera px: larger than tags).
PATTERN_THRESHOLD_WINDOWS = (3, 23, 10)


@dataclass(frozen=True, eq=False)
class PatternSighting:
    """The pattern markers one camera image shows: ids (M,), their corners on the floor (M, 4, 2) m (through the
    camera's floor homography) and in the pattern (M, 4, 2) projector px."""

    ids: NDArray[np.int64]
    floor_corners: NDArray[np.float64]
    pattern_corners: NDArray[np.float64]


def find_pattern(gray: NDArray[np.uint8], pattern: MarkerPattern, floor_homography: NDArray[np.float64],
                 undistort: Callable[[NDArray[np.float64]], NDArray[np.float64]] | None = None) -> PatternSighting:
    """Detect ``pattern``'s markers in a grey camera image and put their corners on the floor: ``undistort``
    (distorted px → undistorted px, e.g. ``CameraCalibration.undistort``; None: the image is undistorted) then
    ``floor_homography`` (undistorted px → m, ``swarmdeck calibrate arena``'s). Ids outside the pattern and ids
    seen twice are dropped."""
    from swarmdeck.tracking.detector import detector_parameters

    det = cv2.aruco.ArucoDetector(dictionary(pattern.dictionary), detector_parameters(PATTERN_THRESHOLD_WINDOWS))
    corners, ids, _ = det.detectMarkers(gray)
    if ids is None or len(ids) == 0:
        return PatternSighting(np.zeros(0, np.int64), np.zeros((0, 4, 2)), np.zeros((0, 4, 2)))
    ids_a = np.asarray(ids, dtype=np.int64).ravel()
    c = np.asarray(corners, dtype=np.float64).reshape(-1, 4, 2)
    uniq, counts = np.unique(ids_a, return_counts=True)
    keep = np.isin(ids_a, uniq[counts == 1]) & (ids_a >= 0) & (ids_a < len(pattern.ids))
    ids_a, c = ids_a[keep], c[keep]
    und = undistort(c) if undistort is not None else c
    return PatternSighting(ids_a, apply_homography(floor_homography, und), pattern.corners_px[ids_a])


def homography_error_mm(H: NDArray[np.float64], truth: NDArray[np.float64],
                        bounds: Bounds | tuple[float, float, float, float], n: int = 21) -> float:
    """Largest distance on the floor, mm, between where ``truth`` and ``H`` (both floor m → projector px) put
    the same projector pixel, over an ``n`` × ``n`` grid of the arena ``bounds``."""
    b = Bounds.of(bounds)
    s = np.linspace(0.0, 1.0, n)
    X, Y = np.meshgrid(b.x_min + s * b.width, b.y_min + s * b.height)
    g = np.column_stack([X.ravel(), Y.ravel()])
    back = apply_homography(np.linalg.inv(H), apply_homography(truth, g))
    return float(np.max(np.linalg.norm(back - g, axis=1))) * 1000.0
