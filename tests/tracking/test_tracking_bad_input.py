"""Bad input never raises into the loop: wrong frames, duplicate ids, robots going missing,
broken pose callables, unreadable sources — each gives a clear status."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.tracking import (
    CameraCalibration,
    CameraError,
    CameraFrame,
    CameraPoseSource,
    ImageFolderSource,
    OpenCVCamera,
    SyntheticCamera,
    SyntheticCameraConfig,
    SyntheticRenderer,
    Tracker,
    TrackerConfig,
    VideoFileSource,
    open_source,
    random_poses,
)


@pytest.fixture(scope="module")
def renderer() -> SyntheticRenderer:
    return SyntheticRenderer(SyntheticCameraConfig())


@pytest.fixture(scope="module")
def poses() -> np.ndarray:
    return random_poses(8, np.random.default_rng(21))


def _tracker(r: SyntheticRenderer, **kw) -> Tracker:
    return Tracker(TrackerConfig(calibration=CameraCalibration.from_camera(r.camera), **kw))


@pytest.mark.parametrize("image, message", [
    (np.zeros((720, 1280, 3), np.float32), "dtype is float32, expected uint8"),
    (np.zeros((720, 1280), np.uint8), "expected (H, W, 3) RGB"),
    (np.zeros((720, 1280, 4), np.uint8), "expected (H, W, 3) RGB"),
    (np.zeros((480, 640, 3), np.uint8), "frame is 640×480 but the calibration is for 1280×720"),
    ("not an image", "frame is str, expected an (H, W, 3) uint8 numpy array"),
])
def test_bad_frames_give_status_not_exceptions(renderer, poses, image, message) -> None:
    tr = _tracker(renderer)
    good = tr.update(CameraFrame(renderer.render(np.arange(8), poses).image, 0.0))
    tp = tr.update(CameraFrame(image, 0.05))
    assert tp.status.startswith("bad frame: ") and message in tp.status
    assert not tp.seen.any() and np.array_equal(tp.poses, good.poses)      # last poses kept, not seen
    assert tr.health()["bad_frames"] == 1


def test_non_finite_stamp_is_rejected(renderer, poses) -> None:
    tp = _tracker(renderer).update(CameraFrame(renderer.render(np.arange(8), poses).image, float("nan")))
    assert "stamp" in tp.status and "finite" in tp.status


def test_duplicate_ids_are_flagged_and_not_used(renderer, poses) -> None:
    ids = np.arange(8)
    tr = _tracker(renderer)
    tr.update(CameraFrame(renderer.render(ids, poses).image, 0.0))
    twin = poses.copy()
    twin[7] = twin[3] + [0.0, 0.0, 0.0]
    twin[7, :2] = [0.0, -0.85] if abs(poses[3, 1] + 0.85) > 0.3 else [0.0, 0.85]
    moved = poses.copy()
    moved[3, 0] += 0.02
    img = renderer.render(np.array([0, 1, 2, 3, 4, 5, 6, 3]), np.vstack([moved[:7], twin[7:]])).image
    tp = tr.update(CameraFrame(img, 0.05))
    assert tp.duplicate_ids == (3,) and "duplicate ids (ignored this frame): 3" in tp.status
    row = np.flatnonzero(tp.ids == 3)[0]
    assert not tp.seen[row] and np.allclose(tp.poses[row], tr.last.poses[row])
    assert abs(tp.poses[row, 0] - poses[3, 0]) < 0.003                       # not the moved or the twin pose
    assert tp.seen[tp.ids != 3].sum() == 6                                   # robot 7 absent, others seen


def test_missing_robot_becomes_stale_and_is_reported(renderer, poses) -> None:
    tr = _tracker(renderer, stale_after_s=0.1)
    ids = np.arange(8)
    tr.update(CameraFrame(renderer.render(ids, poses).image, 0.0))
    frame_without_5 = renderer.render(ids[ids != 5], poses[ids != 5]).image
    tp = tr.update(CameraFrame(frame_without_5, 0.05))
    row = np.flatnonzero(tp.ids == 5)[0]
    assert not tp.seen[row] and not tp.stale[row]                             # one frame missed: not yet stale
    tp = tr.update(CameraFrame(frame_without_5, 2.5))
    assert not tp.seen[row] and tp.stale[row] and tp.stale.sum() == 1
    assert "stale: 5 (2.5 s)" in tp.status
    assert tp.stamps[row] == 0.0                                              # last pose, marked stale
    assert np.allclose(tp.poses[row, :2], poses[5, :2], atol=0.003) and abs(tp.poses[row, 2] - poses[5, 2]) < 0.03
    tp = tr.update(CameraFrame(renderer.render(ids, poses).image, 2.6))
    assert tp.seen[row] and not tp.stale.any() and "stale" not in tp.status


def test_expected_robot_never_seen_is_listed_stale(renderer, poses) -> None:
    tr = _tracker(renderer, expected_ids=(0, 1, 40))
    tp = tr.update(CameraFrame(renderer.render(np.arange(8), poses).image, 0.0))
    row = np.flatnonzero(tp.ids == 40)[0]
    assert tp.stale[row] and np.isnan(tp.poses[row]).all() and "40 (never seen)" in tp.status


def test_pose_callable_errors_become_status(renderer) -> None:
    def broken(t: float) -> np.ndarray:
        raise RuntimeError("simulator gone")
    cam = SyntheticCamera(broken, renderer=renderer)
    src = CameraPoseSource(cam, _tracker(renderer))
    tp = src.read(0.0)
    assert "synthetic camera error: RuntimeError: simulator gone" in tp.status
    assert not cam.ok and src.health()["source_ok"] is False
    cam2 = SyntheticCamera(lambda t: np.zeros((3, 2)), renderer=renderer)     # wrong shape
    assert cam2.read(0.0) is None and "error" in cam2.status


def test_unreadable_sources_report_and_return_none(tmp_path) -> None:
    v = VideoFileSource(tmp_path / "missing.mp4")
    assert v.read(0.0) is None and "no such file" in v.status and not v.ok
    junk = tmp_path / "junk.avi"
    junk.write_bytes(b"this is not a video")
    v = VideoFileSource(junk)
    assert v.read(0.0) is None and "cannot open" in v.status
    folder = tmp_path / "imgs"
    folder.mkdir()
    (folder / "a.png").write_bytes(b"not a png")
    s = ImageFolderSource(folder)
    assert s.read(0.0) is None and "cannot read a.png" in s.status and s.unreadable == 1
    assert "no such folder" in ImageFolderSource(tmp_path / "nope").status
    with pytest.raises(CameraError, match="is not 'synthetic', a webcam index"):
        open_source(str(tmp_path / "nothing-here"))
    with pytest.raises(CameraError, match="needs get_poses"):
        open_source("synthetic")


def test_webcam_that_cannot_open_reports_and_retries() -> None:
    cam = OpenCVCamera("/dev/does-not-exist-swarmdeck", retry_s=0.05)
    try:
        for _ in range(200):                   # poll the thread's status (no timing assertion)
            if "cannot open" in cam.status:
                break
            cam._service.wait(0.01)
        assert "cannot open" in cam.status and cam.read(0.0) is None and not cam.ok
    finally:
        cam.close()
    assert "closed" in cam.status


def test_source_that_raises_is_contained(renderer) -> None:
    class Exploding:
        status = "exploding source"
        ok = True

        def read(self, now: float):
            raise OSError("USB unplugged")

        def close(self) -> None:
            pass

    src = CameraPoseSource(Exploding(), _tracker(renderer))
    tp = src.read(1.0)
    assert "camera error: OSError: USB unplugged" in tp.status
    assert src.health()["source_ok"] is False and "USB unplugged" in src.health()["source"]
