"""swarmdeck.tracking — overhead camera tracking with ArUco tags (issue 9).

Camera sources (webcam, video file, image folder, synthetic renderer) yield
:class:`CameraFrame`; :class:`Tracker` turns frames into :class:`TrackedPoses`;
:class:`CameraPoseSource` does both once per control tick::

    from swarmdeck.tracking import CameraPoseSource
    src = CameraPoseSource.open("synthetic", get_poses=lambda t: arena.poses(), ids=range(n))
    # or CameraPoseSource.open("0" | "rtsp://…" | "video.mp4" | "frames/", config="arena.json")
    tracked = src.read(now)          # TrackedPoses: ids, poses (N, 3), seen, stamps, status, stale
    src.health(); src.status_line(); src.rectified_image(); src.thumbnail(); src.close()
    TrackedPoseSource(src, ids=range(n)).read(now)   # SensedPoses: the control loop's PoseSource

Calibration: ``swarmdeck calibrate camera`` (ChArUco → intrinsics JSON) and
``swarmdeck calibrate arena`` (reference markers → tracker config JSON).
"""
from swarmdeck.tracking.calibration import CalibrationError, CameraCalibration, CharucoSpec, calibrate_charuco
from swarmdeck.tracking.camera_model import PinholeCamera, overhead_camera
from swarmdeck.tracking.config import ConfigError, TrackerConfig
from swarmdeck.tracking.markers import DEFAULT_REFERENCES, ReferenceMarker, marker_corners, poses_from_corners
from swarmdeck.tracking.pose_source import CameraPoseSource, TrackedPoseSource
from swarmdeck.tracking.sources import (
    CameraError,
    CameraSource,
    ImageFolderSource,
    OpenCVCamera,
    VideoFileSource,
    open_source,
)
from swarmdeck.tracking.synthetic import (
    SyntheticCamera,
    SyntheticCameraConfig,
    SyntheticFrame,
    SyntheticRenderer,
    density_image,
    random_poses,
)
from swarmdeck.tracking.tracker import Tracker, check_image
from swarmdeck.tracking.types import CameraFrame, TrackedPoses

__all__ = [
    "CalibrationError", "CameraCalibration", "CameraError", "CameraFrame", "CameraPoseSource", "CameraSource",
    "CharucoSpec", "ConfigError", "DEFAULT_REFERENCES", "ImageFolderSource", "OpenCVCamera", "PinholeCamera",
    "ReferenceMarker", "SyntheticCamera", "SyntheticCameraConfig", "SyntheticFrame", "SyntheticRenderer",
    "TrackedPoseSource", "TrackedPoses", "Tracker", "TrackerConfig", "VideoFileSource", "calibrate_charuco", "check_image", "density_image",
    "marker_corners", "open_source", "overhead_camera", "poses_from_corners", "random_poses",
]
