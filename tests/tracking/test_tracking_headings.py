"""Corner order and heading sign with tags at known headings, checked in the rendered image."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from swarmdeck.tracking import (
    CameraCalibration,
    CameraFrame,
    SyntheticCameraConfig,
    SyntheticRenderer,
    Tracker,
    TrackerConfig,
)
from swarmdeck.tracking.detector import MarkerDetector

HEADINGS = np.array([0.0, np.pi / 2, np.pi, -np.pi / 2, np.pi / 6, -2 * np.pi / 3, 3 * np.pi / 4, -np.pi / 12])


@pytest.fixture(scope="module")
def scene():
    r = SyntheticRenderer(SyntheticCameraConfig(roll=0.0))
    n = len(HEADINGS)
    xy = np.column_stack([np.linspace(-1.2, 1.2, n), np.tile([-0.4, 0.4], n // 2)])
    poses = np.column_stack([xy, HEADINGS])
    return r, poses, r.render(np.arange(n), poses)


def test_detected_corners_follow_the_printed_order(scene) -> None:
    r, poses, f = scene
    det = MarkerDetector("DICT_4X4_50", r.config.references).detect(cv2.cvtColor(f.image, cv2.COLOR_RGB2GRAY))
    for i in range(len(poses)):
        k = np.flatnonzero(det.ids == i)
        assert len(k) == 1
        # corner j of the detection is corner j of the truth (not a rotated/mirrored order)
        assert np.max(np.linalg.norm(det.corners[k[0]] - f.tag_corners_px[i], axis=1)) < 3.0   # side ≈ 22 px


def test_heading_sign_in_image_and_in_tracked_poses(scene) -> None:
    r, poses, f = scene
    det = MarkerDetector("DICT_4X4_50", r.config.references).detect(cv2.cvtColor(f.image, cv2.COLOR_RGB2GRAY))
    c0 = det.corners[np.flatnonzero(det.ids == 0)[0]]       # heading 0: TL → TR points right in the image
    d = c0[1] - c0[0]
    assert d[0] > 20 and abs(d[1]) < 3
    c1 = det.corners[np.flatnonzero(det.ids == 1)[0]]       # heading +90°: TL → TR points up (v decreasing)
    d = c1[1] - c1[0]
    assert d[1] < -20 and abs(d[0]) < 3
    tp = Tracker(TrackerConfig(calibration=CameraCalibration.from_camera(r.camera))).update(CameraFrame(f.image, 0.0))
    err = np.degrees(np.abs(np.angle(np.exp(1j * (tp.poses[:len(poses), 2] - HEADINGS)))))
    assert np.all(tp.ids[:len(poses)] == np.arange(len(poses))) and np.all(err < 2.0)
