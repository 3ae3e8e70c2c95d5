"""Camera intrinsics: the calibration file, point undistortion, and ChArUco calibration.

File format (JSON): ``{"camera_matrix": 3×3, "dist_coeffs": [k1, k2, p1, p2, k3, …],
"image_size": [w, h], "rms_px": float, "n_images": int}``. Undistortion follows the
Robotarium tracker (REFERENCE.md §7): ``cv2.undistortPoints(corners, K, dist, P=K)`` before the
floor homography, iterated to convergence.
"""
from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from swarmdeck.core.checks import in_range
from swarmdeck.core.errors import SwarmdeckError
from swarmdeck.tracking.camera_model import PinholeCamera
from swarmdeck.tracking.dictionaries import canonical_dictionary, dictionary
from swarmdeck.tracking.jsonfile import read_json_object, write_json


class CalibrationError(ValueError, SwarmdeckError):
    """A calibration file or calibration input is unusable (message says why)."""


@dataclass(frozen=True, eq=False)
class CameraCalibration:
    """Intrinsics K (3, 3) px, distortion (k,) OpenCV order, image_size (w, h) px."""

    camera_matrix: np.ndarray
    dist_coeffs: np.ndarray
    image_size: tuple[int, int]
    rms_px: float = float("nan")
    n_images: int = 0

    def undistort(self, pts: np.ndarray) -> np.ndarray:
        """Distorted pixels (..., 2) → undistorted pixels (..., 2) (same K)."""
        p = np.asarray(pts, dtype=np.float64)
        if p.size == 0:
            return p.copy()
        crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 20, 1e-8)
        out = cv2.undistortPointsIter(p.reshape(-1, 1, 2), self.camera_matrix, self.dist_coeffs,  # type: ignore[call-overload]  # cv2's stubs
                                      None, self.camera_matrix, crit)
        return out.reshape(p.shape)

    def distort(self, pts: np.ndarray) -> np.ndarray:
        """Undistorted pixels (..., 2) → distorted pixels (..., 2)."""
        p = np.asarray(pts, dtype=np.float64)
        if p.size == 0:
            return p.copy()
        K = self.camera_matrix
        n = (p.reshape(-1, 2) - K[:2, 2]) / np.array([K[0, 0], K[1, 1]])
        obj = np.column_stack([n, np.ones(len(n))]).reshape(-1, 1, 3)
        out, _ = cv2.projectPoints(obj, np.zeros(3), np.zeros(3), K, self.dist_coeffs)
        return out.reshape(p.shape)

    @staticmethod
    def from_camera(camera: PinholeCamera) -> CameraCalibration:
        """The exact intrinsics of a (synthetic) pinhole camera."""
        return CameraCalibration(camera.K.copy(), camera.dist.copy(), tuple(camera.size), 0.0, 0)  # type: ignore[arg-type]  # (w, h)

    def to_dict(self) -> dict:
        """JSON-able form."""
        return {"camera_matrix": self.camera_matrix.tolist(), "dist_coeffs": self.dist_coeffs.tolist(),
                "image_size": list(self.image_size), "rms_px": float(self.rms_px),
                "n_images": int(self.n_images)}

    @staticmethod
    def from_dict(d: dict) -> CameraCalibration:
        """Parse and check the JSON form (raises :class:`CalibrationError`)."""
        try:
            K = np.asarray(d["camera_matrix"], dtype=float)
            dist = np.asarray(d["dist_coeffs"], dtype=float).reshape(-1)
            size = tuple(int(v) for v in d["image_size"])
        except (KeyError, TypeError, ValueError) as exc:
            raise CalibrationError(f"calibration needs camera_matrix (3×3), dist_coeffs, image_size [w, h]: {exc}") from exc
        if K.shape != (3, 3) or not np.all(np.isfinite(K)) or K[0, 0] <= 0 or K[1, 1] <= 0:
            raise CalibrationError(f"camera_matrix must be a finite 3×3 matrix with fx, fy > 0, got {K.tolist()}")
        if dist.size not in (4, 5, 8, 12, 14) or not np.all(np.isfinite(dist)):
            raise CalibrationError(f"dist_coeffs must have 4, 5, 8, 12 or 14 finite values, got {dist.size}")
        if len(size) != 2 or min(size) <= 0:
            raise CalibrationError(f"image_size must be [w, h] > 0, got {size}")
        return CameraCalibration(K, dist, size, float(d.get("rms_px", float("nan"))), int(d.get("n_images", 0)))

    def save(self, path: str | Path) -> None:
        """Write the JSON file (raises :class:`CalibrationError` naming the path when it cannot)."""
        write_json(path, self.to_dict(), "calibration file", CalibrationError)

    @staticmethod
    def load(path: str | Path) -> CameraCalibration:
        """Read a JSON calibration file (raises :class:`CalibrationError` naming the problem)."""
        d = read_json_object(path, "calibration file", CalibrationError)
        return CameraCalibration.from_dict(d)


@dataclass(frozen=True)
class CharucoSpec:
    """A ChArUco board: squares_x × squares_y squares of ``square_length`` m with markers of
    ``marker_length`` m from ``dictionary`` (5X5_100 by default, so board markers are never
    confused with robot tags)."""

    squares_x: int = 7
    squares_y: int = 5
    square_length: float = 0.04
    marker_length: float = 0.03
    dictionary: str = "DICT_5X5_100"

    def __post_init__(self) -> None:
        try:
            object.__setattr__(self, "dictionary", canonical_dictionary(self.dictionary))
        except ValueError as exc:
            raise CalibrationError(f"ChArUco board dictionary: {exc}") from None
        if not all(in_range(v, 3, integer=True) for v in (self.squares_x, self.squares_y)):
            raise CalibrationError(f"a ChArUco board needs at least 3x3 squares, got {self.squares_x}x{self.squares_y}")
        for name in ("square_length", "marker_length"):
            v = getattr(self, name)
            if not in_range(v, 0.0, lo_open=True):
                raise CalibrationError(f"{name} must be a finite length > 0 m, got {v!r}")
        if self.marker_length >= self.square_length:
            raise CalibrationError(f"marker_length ({self.marker_length} m) must be smaller than "
                                   f"square_length ({self.square_length} m)")

    def board(self) -> cv2.aruco.CharucoBoard:
        """The OpenCV board object."""
        return cv2.aruco.CharucoBoard((self.squares_x, self.squares_y), self.square_length,
                                      self.marker_length, dictionary(self.dictionary))

    def image(self, px_per_square: int = 200, margin_px: int = 40) -> np.ndarray:
        """A printable board image (grey uint8)."""
        size = (self.squares_x * px_per_square + 2 * margin_px, self.squares_y * px_per_square + 2 * margin_px)
        return self.board().generateImage(size, marginSize=margin_px, borderBits=1)


def detect_charuco(image: np.ndarray, spec: CharucoSpec) -> tuple[np.ndarray, np.ndarray]:
    """ChArUco corners in one image → (object points (K, 3) m, image points (K, 2) px)."""
    gray = image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
    board = spec.board()
    det = cv2.aruco.CharucoDetector(board)
    ch_corners, ch_ids, _, _ = det.detectBoard(gray)
    if ch_ids is None or len(ch_ids) < 6:
        return np.zeros((0, 3)), np.zeros((0, 2))
    obj, img = board.matchImagePoints(ch_corners, ch_ids)  # type: ignore[call-overload]  # cv2's stubs
    return obj.reshape(-1, 3), img.reshape(-1, 2)


def calibrate_charuco(images: Iterable[np.ndarray], spec: CharucoSpec = CharucoSpec(),
                      min_views: int = 5) -> CameraCalibration:
    """Intrinsics from ChArUco board views (grey or RGB arrays of one size).

    Views with fewer than 6 board corners are skipped; fewer than ``min_views`` usable views,
    or mixed image sizes, raise :class:`CalibrationError`. Uses ``cv2.calibrateCamera`` with
    the 5-coefficient model.
    """
    obj_pts: list[np.ndarray] = []
    img_pts: list[np.ndarray] = []
    size: tuple[int, int] | None = None
    for im in images:
        s = (im.shape[1], im.shape[0])
        if size is None:
            size = s
        elif s != size:
            raise CalibrationError(f"calibration images differ in size: {size} and {s}")
        o, p = detect_charuco(im, spec)
        if len(o) >= 6 and not _repeats_a_view(o, p, obj_pts, img_pts):
            obj_pts.append(o.astype(np.float32))
            img_pts.append(p.astype(np.float32))
    if size is None or len(obj_pts) < min_views:
        raise CalibrationError(f"found the ChArUco board in {len(obj_pts)} distinct view(s); need at least {min_views} "
                               "(views of the board in different positions and tilts)")
    try:
        rms, K, dist, _, _ = cv2.calibrateCamera(obj_pts, img_pts, size, None, None)
    except cv2.error as exc:
        raise CalibrationError(f"cv2.calibrateCamera failed: {exc.err}") from exc
    if not (np.isfinite(rms) and np.all(np.isfinite(K)) and np.all(np.isfinite(dist)) and K[0, 0] > 0 and K[1, 1] > 0):
        raise CalibrationError(f"calibration did not converge (RMS {rms}, fx {K[0, 0]}, fy {K[1, 1]})")
    return CameraCalibration(K, dist.reshape(-1), size, float(rms), len(obj_pts))


def _repeats_a_view(obj: np.ndarray, img: np.ndarray, objs: list[np.ndarray], imgs: list[np.ndarray],
                    tol_px: float = 1.0) -> bool:
    """True when the same board corners were already seen within ``tol_px`` (RMS) of these
    image positions: a repeated view adds no information but would make the fit look confident."""
    for o, p in zip(objs, imgs):
        if o.shape == obj.shape and np.array_equal(o, obj.astype(np.float32)):
            if float(np.sqrt(np.mean(np.sum((p - img) ** 2, axis=1)))) < tol_px:
                return True
    return False
