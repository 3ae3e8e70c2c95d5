"""The ArUco detector with swarmdeck's settings (REFERENCE.md §7).

``CORNER_REFINE_SUBPIX`` with ``relativeCornerRefinmentWinSize = 1.0`` (API spelling): corner
RMS 0.23 px on 26 px tags against 0.6–0.8 px with the defaults; no ``useAruco3Detection``
(finds no tag under 32 px). Reference markers are re-found every frame with
``refineDetectedMarkers`` against a ``Board`` of their surveyed corners.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from swarmdeck.tracking.dictionaries import dictionary
from swarmdeck.tracking.markers import ReferenceMarker, reference_corners


@dataclass(frozen=True, eq=False)
class Detections:
    """ids (M,) int and corners (M, 4, 2) float64 distorted pixels, OpenCV corner order;
    recovered: how many reference markers ``refineDetectedMarkers`` found in the rejects."""

    ids: np.ndarray
    corners: np.ndarray
    recovered: int = 0


DEFAULT_THRESHOLD_WINDOWS = (7, 17, 10)


def detector_parameters(threshold_windows: tuple[int, int, int] = DEFAULT_THRESHOLD_WINDOWS,
                        ) -> cv2.aruco.DetectorParameters:
    """DetectorParameters of REFERENCE.md §7, plus the adaptive-threshold windows
    (min, max, step) px: (7, 17, 10) = two passes instead of OpenCV's three (3, 13, 23) — 1.7×
    faster at 1920×1080 with no loss of detections on 20–35 px tags (bench/bench_tracking.py);
    use (3, 23, 10) for OpenCV's default, or larger windows for tags over ~60 px."""
    p = cv2.aruco.DetectorParameters()
    p.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    p.relativeCornerRefinmentWinSize = 1.0
    p.useAruco3Detection = False
    p.adaptiveThreshWinSizeMin, p.adaptiveThreshWinSizeMax, p.adaptiveThreshWinSizeStep = (
        int(v) for v in threshold_windows)
    # read the bits from an 8 px-per-cell canonical image instead of 4: on 20–30 px tags with a
    # narrow white plate the coarser sampling misread about 1 tag in 2000 (bench notes)
    p.perspectiveRemovePixelPerCell = 8
    return p


class MarkerDetector:
    """Detects tags of one dictionary and recovers missed reference markers."""

    def __init__(self, dict_name: str, references: tuple[ReferenceMarker, ...],
                 camera_matrix: np.ndarray | None = None, dist_coeffs: np.ndarray | None = None,
                 threshold_windows: tuple[int, int, int] = DEFAULT_THRESHOLD_WINDOWS) -> None:
        self._dict = dictionary(dict_name)
        self._det = cv2.aruco.ArucoDetector(self._dict, detector_parameters(threshold_windows),
                                            cv2.aruco.RefineParameters())
        ref_ids, ref_c = reference_corners(references)
        self._ref_ids = ref_ids
        self._board = None
        if len(references) > 0:
            obj = [np.column_stack([c, np.zeros(4)]).astype(np.float32) for c in ref_c]
            self._board = cv2.aruco.Board(obj, self._dict, ref_ids.astype(np.int32))
        self._K = camera_matrix
        self._dist = dist_coeffs

    def detect(self, gray: np.ndarray) -> Detections:
        """Detect in a grey uint8 image; then re-find missing references among the rejected
        candidates (when at least one reference was found)."""
        corners, ids, rejected = self._det.detectMarkers(gray)
        return self.recover_references(gray, corners, ids, rejected)  # type: ignore[arg-type]  # cv2's stubs

    def recover_references(self, gray: np.ndarray, corners: tuple, ids: np.ndarray | None,
                           rejected: tuple) -> Detections:
        """``refineDetectedMarkers`` against the reference board (PnP with the calibration when
        there is one, else a homography) for references missing from ``ids`` → Detections."""
        recovered = 0
        if self._board is not None and ids is not None and len(rejected) > 0:
            found = np.isin(self._ref_ids, np.asarray(ids).ravel())
            if found.any() and not found.all():
                if self._K is not None:
                    corners, ids, rejected, rec = self._det.refineDetectedMarkers(  # type: ignore[assignment]  # cv2's stubs
                        gray, self._board, corners, ids, rejected, self._K, self._dist)
                else:
                    corners, ids, rejected, rec = self._det.refineDetectedMarkers(  # type: ignore[assignment]  # cv2's stubs
                        gray, self._board, corners, ids, rejected)
                recovered = 0 if rec is None else len(rec)
        if ids is None or len(ids) == 0:
            return Detections(np.zeros(0, dtype=int), np.zeros((0, 4, 2)), recovered)
        c = np.asarray(corners, dtype=np.float64).reshape(-1, 4, 2)
        return Detections(np.asarray(ids, dtype=int).reshape(-1), c, recovered)
