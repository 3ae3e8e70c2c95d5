"""Without a homography (too few reference markers and no fallback), robot markers in the
frame cannot be placed: the status says the homography is missing and which markers were
seen, instead of "0/6 robots seen; stale: 23 (never seen)"."""
from __future__ import annotations

import cv2
import numpy as np

from swarmdeck.tracking import Tracker, TrackerConfig
from swarmdeck.tracking.dictionaries import dictionary
from swarmdeck.tracking.types import CameraFrame


def frame_with_tags(ids, t=1.0) -> CameraFrame:
    d = dictionary("DICT_4X4_50")
    img = np.full((240, 160 * len(ids) + 40, 3), 255, np.uint8)
    for k, i in enumerate(ids):
        tag = cv2.aruco.generateImageMarker(d, int(i), 120, borderBits=1)
        img[60:180, 40 + 160 * k:160 + 160 * k] = tag[..., None]
    return CameraFrame(img, t, 0, t)


def test_markers_seen_without_a_homography_are_reported_as_unplaced():
    tracker = Tracker(TrackerConfig(expected_ids=(1, 2, 3, 4, 5, 23)))
    tp = tracker.update(frame_with_tags([23, 5]))
    assert tracker.homography is None and tp.homography == "none"
    assert not tp.seen.any()  # no pose could be computed
    status = tp.status
    assert "no homography" in status
    assert "robot markers 5, 23 seen but not placed: no homography yet" in status
    assert "23 (never seen)" not in status and "5 (never seen)" not in status
    assert "1 (never seen)" in status  # robot 1 really was never seen
    h = tracker.health()
    assert h["homography"] == "none" and h["robots_unplaced"] == 2 and h["robots_seen"] == 0


def test_with_a_homography_nothing_is_unplaced():
    H = ((0.01, 0.0, -1.0), (0.0, -0.01, 1.0), (0.0, 0.0, 1.0))
    tracker = Tracker(TrackerConfig(expected_ids=(5, 23), fallback_homography=H))
    tp = tracker.update(frame_with_tags([23, 5]))
    assert tp.seen.all() and "not placed" not in tp.status and tracker.health()["robots_unplaced"] == 0
