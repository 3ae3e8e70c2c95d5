"""Frames → robot poses: detection, undistortion, floor homography, parallax, bookkeeping.

One call per frame, :meth:`Tracker.update`; it never raises on bad frames — the reason goes
into ``TrackedPoses.status`` and the counters. Robots keep their last pose with ``seen`` False
and become ``stale`` after ``stale_after_s``; they are never silently frozen.
"""
from __future__ import annotations

import math

import cv2
import numpy as np

from swarmdeck.tracking.config import TrackerConfig
from swarmdeck.tracking.detector import Detections, MarkerDetector
from swarmdeck.tracking.homography import (
    HomographyFit,
    apply_homography,
    camera_centre_from_homography,
    correct_parallax,
    fit_floor_homography,
)
from swarmdeck.tracking.markers import poses_from_corners, reference_corners
from swarmdeck.tracking.types import CameraFrame, TrackedPoses


def check_image(image: object, expected_size: tuple[int, int] | None = None) -> str | None:
    """None when ``image`` is an (H, W, 3) uint8 array (of ``expected_size`` (w, h) if given),
    else a message saying what is wrong."""
    if not isinstance(image, np.ndarray):
        return f"frame is {type(image).__name__}, expected an (H, W, 3) uint8 numpy array"
    if image.dtype != np.uint8:
        return f"frame dtype is {image.dtype}, expected uint8"
    if image.ndim != 3 or image.shape[2] != 3:
        return f"frame shape is {image.shape}, expected (H, W, 3) RGB"
    if image.shape[0] < 16 or image.shape[1] < 16:
        return f"frame {image.shape[1]}×{image.shape[0]} is too small"
    if expected_size is not None and (image.shape[1], image.shape[0]) != tuple(expected_size):
        return (f"frame is {image.shape[1]}×{image.shape[0]} but the calibration is for "
                f"{expected_size[0]}×{expected_size[1]}")
    return None


def _id_list(ids: np.ndarray, extra: np.ndarray | None = None, limit: int = 8) -> str:
    items = [f"{int(i)}" if extra is None else f"{int(i)} ({e:.1f} s)" for i, e in
             zip(ids[:limit], extra[:limit] if extra is not None else ids[:limit])]
    return ", ".join(items) + (f", … ({len(ids)} in all)" if len(ids) > limit else "")


class Tracker:
    """Stateful ArUco tracker for one camera (see module docstring)."""

    def __init__(self, config: TrackerConfig = TrackerConfig()) -> None:
        self.config = config
        cal = config.calibration
        self._detector = MarkerDetector(config.dictionary, config.references,
                                        None if cal is None else cal.camera_matrix,
                                        None if cal is None else cal.dist_coeffs, config.threshold_windows)
        ref_ids, ref_c = reference_corners(config.references)
        order = np.argsort(ref_ids)
        self._ref_ids = ref_ids[order]
        self._ref_corners = ref_c[order]
        self._ids = np.array(sorted(set(config.expected_ids)), dtype=int)
        self._poses = np.full((len(self._ids), 3), np.nan)
        self._stamps = np.full(len(self._ids), -np.inf)
        self._H: np.ndarray | None = None
        self._H_kind = "none"
        self._H_stamp = -math.inf
        if config.fallback_homography is not None:
            self._H = np.asarray(config.fallback_homography, dtype=float)
            self._H_kind = "fallback"
        self._centre: np.ndarray | None = None
        self._update_centre()
        self.last_detections = Detections(np.zeros(0, int), np.zeros((0, 4, 2)))
        self._unplaced = np.zeros(0, dtype=int)  # robot ids in the last frame that had no homography
        self.last_fit: HomographyFit | None = None
        self.last: TrackedPoses = self._snapshot(float("nan"), np.zeros(len(self._ids), bool), "no frame yet")
        self.counters = {"frames": 0, "bad_frames": 0, "rejected_homographies": 0, "duplicate_frames": 0}

    # -- state ------------------------------------------------------------------------------
    @property
    def homography(self) -> np.ndarray | None:
        """The homography in use (undistorted px → arena m on the reference plane), or None."""
        return None if self._H is None else self._H.copy()

    @property
    def camera_centre(self) -> np.ndarray | None:
        """Camera centre (x, y, height above the reference plane) in m, when known."""
        return None if self._centre is None else self._centre.copy()

    def _update_centre(self) -> None:
        cfg = self.config
        if self._H is not None and cfg.calibration is not None:
            c = camera_centre_from_homography(self._H, cfg.calibration.camera_matrix)
            if c is not None:
                self._centre = c
                return
        if cfg.camera_position is not None:
            self._centre = np.asarray(cfg.camera_position, dtype=float)

    def _snapshot(self, now: float, seen: np.ndarray, status: str, dup: tuple[int, ...] = ()) -> TrackedPoses:
        stale = (now - self._stamps) > self.config.stale_after_s if math.isfinite(now) else \
            np.ones(len(self._ids), bool)
        return TrackedPoses(ids=self._ids.copy(), poses=self._poses.copy(), seen=seen.copy(),
                            stamps=self._stamps.copy(), status=status, frame_stamp=now, stale=stale,
                            duplicate_ids=dup, homography=self._H_kind)

    def poses_at(self, now: float, status: str | None = None) -> TrackedPoses:
        """The current state without a new frame: nobody ``seen``, staleness judged at ``now``."""
        base = self.last.status if status is None else status
        tp = self._snapshot(now, np.zeros(len(self._ids), bool), base, self.last.duplicate_ids)
        return TrackedPoses(tp.ids, tp.poses, tp.seen, tp.stamps, tp.status, self.last.frame_stamp, tp.stale,
                            tp.duplicate_ids, tp.homography)

    # -- one frame --------------------------------------------------------------------------
    def update(self, frame: CameraFrame) -> TrackedPoses:
        """Process one frame → :class:`TrackedPoses` (never raises on bad input)."""
        self.counters["frames"] += 1
        cfg = self.config
        stamp = frame.stamp if isinstance(frame, CameraFrame) else float("nan")
        image = frame.image if isinstance(frame, CameraFrame) else frame
        err = check_image(image, None if cfg.calibration is None else cfg.calibration.image_size)
        if err is None and not (isinstance(stamp, (int, float)) and math.isfinite(stamp)):
            err = f"frame stamp {stamp!r} is not a finite number of seconds"
        if err is not None:
            self.counters["bad_frames"] += 1
            self._unplaced = np.zeros(0, dtype=int)
            now = stamp if isinstance(stamp, (int, float)) and math.isfinite(stamp) else self.last.frame_stamp
            self.last = self._snapshot(now, np.zeros(len(self._ids), bool), f"bad frame: {err}")
            return self.last
        gray = cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)
        det = self._detector.detect(gray)
        self.last_detections = det
        ids = det.ids
        und = det.corners if cfg.calibration is None else cfg.calibration.undistort(det.corners)
        uniq, counts = np.unique(ids, return_counts=True)
        dup = uniq[counts > 1]
        if dup.size:
            self.counters["duplicate_frames"] += 1
        good = ~np.isin(ids, dup)
        is_ref = good & np.isin(ids, self._ref_ids)
        k = np.searchsorted(self._ref_ids, ids[is_ref])
        fit = fit_floor_homography(und[is_ref], self._ref_corners[k], (image.shape[1], image.shape[0]),
                                   cfg.min_references, cfg.max_reference_rms_m, cfg.max_anisotropy)
        self.last_fit = fit
        n_refs = f"{int(is_ref.sum())}/{len(self._ref_ids)} references"
        if fit.ok:
            self._H, self._H_kind, self._H_stamp = fit.H, "ok", stamp
            self._update_centre()
            h_status = f"homography ok ({n_refs}, {fit.rms_m * 1000:.1f} mm RMS)"
        else:
            self.counters["rejected_homographies"] += 1
            if self._H is None:
                self._H_kind = "none"
                h_status = f"no homography: {fit.reason} ({n_refs})"
            elif math.isfinite(self._H_stamp):
                self._H_kind = "held"
                h_status = (f"homography held ({n_refs}): {fit.reason}; using the last good one from "
                            f"{stamp - self._H_stamp:.1f} s ago")
            else:
                self._H_kind = "fallback"
                h_status = f"fallback homography ({n_refs}): {fit.reason}"

        robots = good & ~np.isin(ids, self._ref_ids)
        new_ids = ids[robots]
        seen_ids = np.zeros(0, dtype=int)
        parallax_note = ""
        if self._H is not None and new_ids.size:
            arena = apply_homography(self._H, und[robots])
            dh = cfg.tag_height - cfg.reference_height
            if dh != 0.0:
                if self._centre is not None:
                    arena = correct_parallax(arena, self._centre, dh)
                else:
                    parallax_note = "parallax not corrected (no calibration or camera_position)"
            poses = poses_from_corners(arena)
            self._merge(new_ids, poses, stamp)
            seen_ids = new_ids
        elif new_ids.size:
            self._merge(new_ids, None, stamp)
        # robot markers in this frame that got no pose: no homography to place them with
        unplaced = np.unique(new_ids) if self._H is None else np.zeros(0, dtype=int)
        self._unplaced = unplaced
        seen = np.isin(self._ids, seen_ids)
        parts = [h_status]
        if unplaced.size:
            parts.append(f"robot markers {_id_list(unplaced)} seen but not placed: no homography yet")
        parts.append(f"{int(seen.sum())}/{len(self._ids)} robots seen")
        tp = self._snapshot(stamp, seen, "", tuple(int(i) for i in dup))
        if tp.stale.any():
            st = np.flatnonzero(tp.stale)
            ages = stamp - self._stamps[st]
            ids_st = self._ids[st]
            in_frame = np.isin(ids_st, unplaced)
            parts.append("stale: " + ", ".join(
                f"{int(i)} ({a:.1f} s)" if math.isfinite(a) else
                f"{int(i)} ({'in view, no homography' if f else 'never seen'})"
                for i, a, f in zip(ids_st[:8], ages[:8], in_frame[:8]))
                + (f", … ({len(st)} in all)" if len(st) > 8 else ""))
        if dup.size:
            parts.append(f"duplicate ids (ignored this frame): {_id_list(dup)}")
        if parallax_note:
            parts.append(parallax_note)
        self.last = TrackedPoses(tp.ids, tp.poses, tp.seen, tp.stamps, "; ".join(parts), stamp, tp.stale,
                                 tp.duplicate_ids, self._H_kind)
        return self.last

    def _merge(self, new_ids: np.ndarray, poses: np.ndarray | None, stamp: float) -> None:
        """Add unseen ids (NaN pose, never seen) and write new poses and stamps (vectorised)."""
        all_ids = np.union1d(self._ids, new_ids)
        if len(all_ids) != len(self._ids):
            P = np.full((len(all_ids), 3), np.nan)
            S = np.full(len(all_ids), -np.inf)
            k = np.searchsorted(all_ids, self._ids)
            P[k], S[k] = self._poses, self._stamps
            self._ids, self._poses, self._stamps = all_ids, P, S
        if poses is not None:
            k = np.searchsorted(self._ids, new_ids)
            self._poses[k] = poses
            self._stamps[k] = stamp

    def health(self) -> dict:
        """JSON-able tracking health: markers and references seen, homography state."""
        fit = self.last_fit
        return {
            "markers_seen": int(len(self.last_detections.ids)),
            "references_seen": 0 if fit is None else int(fit.n_references),
            "references_total": int(len(self._ref_ids)),
            "homography": self._H_kind,
            "homography_reason": "" if fit is None else fit.reason,
            "reference_rms_mm": None if fit is None or not math.isfinite(fit.rms_m) else fit.rms_m * 1000,
            "robots_seen": int(self.last.seen.sum()),
            "robots_unplaced": int(len(self._unplaced)),
            "robots_stale": int(self.last.stale.sum()),
            "duplicate_ids": list(self.last.duplicate_ids),
            **self.counters,
        }
