"""Loss and recovery of the reference markers: held homography with a status, no homography
before the first good fit, recovery when they come back; misdetections rejected."""
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
    random_poses,
)


@pytest.fixture(scope="module")
def scene():
    r = SyntheticRenderer(SyntheticCameraConfig())
    poses = random_poses(12, np.random.default_rng(5))
    frame = r.render(np.arange(12), poses)
    return r, poses, frame


def _hide(image: np.ndarray, corners_px: np.ndarray, which: list[int]) -> np.ndarray:
    """Cover reference markers ``which`` with floor-coloured patches (as a person's arm would)."""
    out = image.copy()
    for k in which:
        c = corners_px[k]
        centre = c.mean(axis=0)
        poly = centre + 1.8 * (c - centre)
        cv2.fillPoly(out, [np.round(poly).astype(np.int32)], (150, 147, 141))
    return out


def _config(r: SyntheticRenderer) -> TrackerConfig:
    return TrackerConfig(calibration=CameraCalibration.from_camera(r.camera))


def test_loss_holds_last_good_homography_and_recovers(scene) -> None:
    r, poses, f = scene
    tr = Tracker(_config(r))
    tp = tr.update(CameraFrame(f.image, 0.0))
    assert tp.homography == "ok" and tp.seen.all()
    H_good = tr.homography
    for t, hidden in [(0.1, [0, 1]), (0.2, [0, 1, 2, 3])]:
        tp = tr.update(CameraFrame(_hide(f.image, f.reference_corners_px, hidden), t))
        assert tp.homography == "held"
        assert f"{4 - len(hidden)}/4 references" in tp.status and "last good one" in tp.status
        assert np.array_equal(tr.homography, H_good)
        assert tp.seen.all()                                   # robots still tracked with the held H
        assert np.max(np.hypot(*(tp.poses[:, :2] - poses[:, :2]).T)) < 0.003
    tp = tr.update(CameraFrame(f.image, 0.3))
    assert tp.homography == "ok" and "homography ok (4/4 references" in tp.status
    assert tr.health()["rejected_homographies"] == 2


def test_three_references_are_enough(scene) -> None:
    r, poses, f = scene
    tp = Tracker(_config(r)).update(CameraFrame(_hide(f.image, f.reference_corners_px, [2]), 0.0))
    assert tp.homography == "ok" and "3/4 references" in tp.status
    assert np.max(np.hypot(*(tp.poses[:, :2] - poses[:, :2]).T)) < 0.003


def test_no_references_from_the_start_gives_no_poses_and_says_why(scene) -> None:
    r, poses, f = scene
    tr = Tracker(_config(r).with_(expected_ids=tuple(range(12))))
    tp = tr.update(CameraFrame(_hide(f.image, f.reference_corners_px, [0, 1, 2, 3]), 0.0))
    assert tp.homography == "none"
    assert "no homography: 0 reference marker(s) visible, need 3" in tp.status
    assert not tp.seen.any() and tp.stale.all() and np.isnan(tp.poses).all()
    tp = tr.update(CameraFrame(f.image, 0.05))
    assert tp.homography == "ok" and tp.seen.all()


def test_fallback_homography_until_first_good_fit(scene) -> None:
    r, poses, f = scene
    tr0 = Tracker(_config(r))
    tr0.update(CameraFrame(f.image, 0.0))
    H = tuple(tuple(row) for row in tr0.homography)
    tr = Tracker(_config(r).with_(fallback_homography=H))
    tp = tr.update(CameraFrame(_hide(f.image, f.reference_corners_px, [0, 1, 2, 3]), 0.0))
    assert tp.homography == "fallback" and "fallback homography" in tp.status and tp.seen.all()
    assert np.max(np.hypot(*(tp.poses[:, :2] - poses[:, :2]).T)) < 0.003


def test_wrongly_surveyed_layout_is_rejected(scene) -> None:
    """A reference recorded 3 cm off in size (wrong print scale) cannot be fitted: rejected."""
    r, poses, f = scene
    refs = list(r.config.references)
    refs[1] = type(refs[1])(refs[1].id, refs[1].x, refs[1].y, size=refs[1].size * 1.3)
    tp = Tracker(_config(r).with_(references=tuple(refs))).update(CameraFrame(f.image, 0.0))
    assert tp.homography == "none" and "misdetected or moved" in tp.status


def test_reference_among_rejected_candidates_is_recovered_by_refinement(scene) -> None:
    """A reference whose quad ended up among the rejected candidates (unreadable bits) is
    re-found by refineDetectedMarkers from the other references and the calibration."""
    from swarmdeck.tracking.detector import MarkerDetector, detector_parameters

    r, poses, f = scene
    gray = cv2.cvtColor(f.image, cv2.COLOR_RGB2GRAY)
    d = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
    corners, ids, rejected = cv2.aruco.ArucoDetector(d, detector_parameters()).detectMarkers(gray)
    lost = r.config.references[1].id
    k = int(np.flatnonzero(ids.ravel() == lost)[0])
    corners2 = tuple(c for j, c in enumerate(corners) if j != k)
    ids2 = np.delete(ids, k, axis=0)
    rejected2 = tuple(rejected) + (corners[k],)
    cal = CameraCalibration.from_camera(r.camera)
    det = MarkerDetector("DICT_4X4_50", r.config.references, cal.camera_matrix, cal.dist_coeffs)
    out = det.recover_references(gray, corners2, ids2, rejected2)
    assert lost in out.ids and out.recovered == 1
    row = int(np.flatnonzero(out.ids == lost)[0])
    assert np.allclose(out.corners[row], corners[k].reshape(4, 2), atol=0.2)   # corners re-refined
    # nothing to recover when all references were found
    assert det.recover_references(gray, corners, ids, rejected).recovered == 0
