"""Tracker configuration (a frozen dataclass, defaults from REFERENCE.md §7) and its JSON file.

The arena file written by ``swarmdeck calibrate arena`` is this dataclass as JSON::

    {"dictionary": "DICT_4X4_50", "tag_size": 0.08, "tag_height": 0.06,
     "reference_height": 0.0, "references": [{"id": 46, "x": -1.7, "y": -1.1, "size": 0.1,
     "heading": 0.0}, ...], "camera_position": [x, y, z] | null,
     "fallback_homography": 3×3 | null, "calibration": {...} | null, ...}
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.checks import in_range
from swarmdeck.core.config import ConfigError, check_keys, field_names
from swarmdeck.tracking.calibration import CalibrationError, CameraCalibration
from swarmdeck.tracking.dictionaries import canonical_dictionary
from swarmdeck.tracking.jsonfile import read_json_object, write_json
from swarmdeck.tracking.markers import DEFAULT_REFERENCES, ReferenceMarker


@dataclass(frozen=True, eq=False)
class TrackerConfig:
    """Everything the tracker needs to know about the arena and the camera.

    dictionary: marker dictionary of all tags: any predefined OpenCV ArUco dictionary or
    AprilTag family, case-insensitive (stored by its canonical name, e.g. DICT_APRILTAG_36h11). references: surveyed reference markers (ids
    never used by robots). tag_height / reference_height: heights (m) of robot tags and of the
    reference markers above the floor; their difference is corrected as parallax. stale_after_s:
    a robot not seen for longer is stale (0.1 s: the Robotarium's monitor zeroes robots whose
    poses are older, REFERENCE.md §9). expected_ids: robots listed even before they are first
    seen (NaN pose, stale). min_references / max_reference_rms_m / max_anisotropy: homography
    acceptance. camera_position: (x, y, height above the reference plane) m, used for parallax
    when there is no calibration. fallback_homography: undistorted px → m, used until the first
    good fit. calibration: intrinsics (None: no undistortion). bounds: arena rectangle.
    """

    dictionary: str = "DICT_4X4_50"
    references: tuple[ReferenceMarker, ...] = DEFAULT_REFERENCES
    tag_size: float = 0.08
    tag_height: float = 0.06
    reference_height: float = 0.0
    stale_after_s: float = 0.1
    expected_ids: tuple[int, ...] = ()
    min_references: int = 3
    max_reference_rms_m: float = 0.01
    max_anisotropy: float = 10.0
    camera_position: tuple[float, float, float] | None = None
    fallback_homography: tuple[tuple[float, ...], ...] | None = None
    calibration: CameraCalibration | None = None
    bounds: Bounds = DEFAULT_BOUNDS
    threshold_windows: tuple[int, int, int] = (7, 17, 10)

    def __post_init__(self) -> None:
        try:
            object.__setattr__(self, "dictionary", canonical_dictionary(self.dictionary))
        except ValueError as exc:
            raise ConfigError(f"dictionary: {exc}") from None
        if not in_range(self.tag_size, 0.0, 1.0, lo_open=True, hi_open=True):
            raise ConfigError(f"tag_size must be in (0, 1) m, got {self.tag_size}")
        if not in_range(self.stale_after_s, 0.0, lo_open=True):
            raise ConfigError(f"stale_after_s must be a finite number > 0 s, got {self.stale_after_s}")
        for name in ("tag_height", "reference_height"):  # NaN here would make every pose NaN
            v = getattr(self, name)
            if not in_range(v, 0.0, 10.0, hi_open=True):
                raise ConfigError(f"{name} must be a height in [0, 10) m above the floor, got {v}")
        for name in ("max_reference_rms_m", "max_anisotropy"):
            v = getattr(self, name)
            if not in_range(v, 0.0, lo_open=True):
                raise ConfigError(f"{name} must be a finite number > 0, got {v}")
        if not in_range(self.min_references, 1, integer=True):
            raise ConfigError(f"min_references must be >= 1, got {self.min_references}")
        ids = [r.id for r in self.references]
        if len(set(ids)) != len(ids):
            raise ConfigError(f"reference ids must be distinct, got {ids}")
        if set(ids) & set(self.expected_ids):
            raise ConfigError(f"expected robot ids {sorted(set(ids) & set(self.expected_ids))} are reference ids")
        if self.camera_position is not None and (len(self.camera_position) != 3 or not self.camera_position[2] > 0
                                                 or not np.all(np.isfinite(self.camera_position))):
            raise ConfigError(f"camera_position must be (x, y, height > 0), got {self.camera_position}")
        tw = tuple(self.threshold_windows)
        if len(tw) != 3 or not (3 <= tw[0] <= tw[1]) or tw[2] < 1:
            raise ConfigError(f"threshold_windows must be (min, max, step) with 3 <= min <= max, step >= 1, got {tw}")
        if self.fallback_homography is not None and np.asarray(self.fallback_homography).shape != (3, 3):
            raise ConfigError("fallback_homography must be 3×3")

    def with_(self, **changes: Any) -> TrackerConfig:
        """A copy with some fields replaced."""
        return replace(self, **changes)

    def to_dict(self) -> dict:
        """JSON-able form."""
        d = {f.name: getattr(self, f.name) for f in fields(self)}
        d["references"] = [asdict(r) for r in self.references]
        d["expected_ids"] = list(self.expected_ids)
        d["bounds"] = list(self.bounds)
        d["threshold_windows"] = list(self.threshold_windows)
        d["camera_position"] = None if self.camera_position is None else [float(v) for v in self.camera_position]
        d["fallback_homography"] = None if self.fallback_homography is None else \
            np.asarray(self.fallback_homography, float).tolist()
        d["calibration"] = None if self.calibration is None else self.calibration.to_dict()
        return d

    @staticmethod
    def from_dict(d: dict) -> TrackerConfig:
        """Parse the JSON form; unknown keys and bad values raise :class:`ConfigError`."""
        kw = check_keys(d, field_names(TrackerConfig), "tracker config")
        try:
            if "references" in kw:
                kw["references"] = tuple(ReferenceMarker(int(r["id"]), float(r["x"]), float(r["y"]),
                                                         float(r.get("size", 0.10)), float(r.get("heading", 0.0)))
                                         for r in kw["references"])
            if "expected_ids" in kw:
                kw["expected_ids"] = tuple(int(i) for i in kw["expected_ids"])
            if "bounds" in kw:
                kw["bounds"] = tuple(float(v) for v in kw["bounds"])
            if "threshold_windows" in kw:
                kw["threshold_windows"] = tuple(int(v) for v in kw["threshold_windows"])
            if kw.get("camera_position") is not None:
                kw["camera_position"] = tuple(float(v) for v in kw["camera_position"])
            if kw.get("fallback_homography") is not None:
                kw["fallback_homography"] = tuple(tuple(float(v) for v in row) for row in kw["fallback_homography"])
            if kw.get("calibration") is not None:
                kw["calibration"] = CameraCalibration.from_dict(kw["calibration"])
            for k in ("tag_size", "tag_height", "reference_height", "stale_after_s", "max_reference_rms_m",
                      "max_anisotropy"):
                if k in kw:
                    kw[k] = float(kw[k])
            if "min_references" in kw:
                kw["min_references"] = int(kw["min_references"])
        except (KeyError, TypeError, ValueError) as exc:
            if isinstance(exc, (ConfigError, CalibrationError)):
                raise
            raise ConfigError(f"bad tracker config value: {exc}") from exc
        return TrackerConfig(**kw)

    def save(self, path: str | Path) -> None:
        """Write the JSON file (raises :class:`ConfigError` naming the path when it cannot)."""
        write_json(path, self.to_dict(), "tracker config", ConfigError)

    @staticmethod
    def load(path: str | Path) -> TrackerConfig:
        """Read a JSON file written by :meth:`save` or ``swarmdeck calibrate arena``."""
        d = read_json_object(path, "tracker config", ConfigError)
        return TrackerConfig.from_dict(d)
