"""CameraPoseSource driven like the console loop: a simulator's poses → synthetic camera →
tracked poses each tick on a virtual clock; health, thumbnail and the rectified floor image."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from swarmdeck.tracking import (
    CameraCalibration,
    CameraPoseSource,
    SyntheticCamera,
    SyntheticCameraConfig,
    SyntheticRenderer,
    Tracker,
    TrackerConfig,
    random_poses,
)


class MovingRobots:
    """A stand-in simulator: robots drive forward at 0.1 m/s along their headings."""

    def __init__(self, n: int) -> None:
        self.p0 = random_poses(n, np.random.default_rng(4), margin=0.35, min_distance=0.25)

    def poses(self, t: float) -> np.ndarray:
        p = self.p0.copy()
        p[:, 0] += 0.1 * t * np.cos(p[:, 2])
        p[:, 1] += 0.1 * t * np.sin(p[:, 2])
        return p


@pytest.fixture(scope="module")
def setup():
    r = SyntheticRenderer(SyntheticCameraConfig())
    sim = MovingRobots(10)
    cam = SyntheticCamera(sim.poses, ids=range(10), renderer=r)
    tracker = Tracker(TrackerConfig(calibration=CameraCalibration.from_camera(r.camera), expected_ids=tuple(range(10))))
    return r, sim, CameraPoseSource(cam, tracker)


def test_loop_ticks_track_moving_robots(setup) -> None:
    r, sim, src = setup
    dt = 0.033
    for k in range(4):
        t = k * dt
        tp = src.read(t)
        truth = sim.poses(t)
        assert tp.seen.all() and not tp.stale.any() and tp.frame_stamp == t
        assert np.all(tp.stamps == t)
        assert np.max(np.hypot(*(tp.poses[:, :2] - truth[:, :2]).T)) < 0.003
    h = src.health()
    for key in ("fps", "latency_ms", "processing_ms", "markers_seen", "references_seen", "homography", "source"):
        assert key in h
    assert h["markers_seen"] == 14 and h["references_seen"] == 4 and h["homography"] == "ok"
    assert h["latency_ms"] > 0 and h["frames"] >= 4
    assert "refs 4/4, homography ok" in src.status_line()


def test_thumbnail_and_rectified_floor_line_up_with_poses(setup) -> None:
    r, sim, src = setup
    tp = src.read(0.2)
    thumb = src.thumbnail()
    assert thumb.shape == (180, 320, 3) and thumb.dtype == np.uint8
    src.px_per_m = 500.0
    src._rect_cache = None
    img, bounds = src.rectified_image()
    x0, x1, y0, y1 = bounds
    assert img.shape == (1000, 1600, 3) and img.dtype == np.uint8
    # the tags, found again in the top-down picture, sit where the tracked poses say (≤ 2 px = 4 mm)
    det = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50))
    corners, ids, _ = det.detectMarkers(cv2.cvtColor(img, cv2.COLOR_RGB2GRAY))
    assert ids is not None
    found = 0
    for c, i in zip(corners, ids.ravel()):
        if i >= 10:
            continue
        u, v = c.reshape(4, 2).mean(axis=0)
        x = x0 + (u + 0.5) / 500.0
        y = y1 - (v + 0.5) / 500.0
        pose = tp.pose_of(int(i))
        assert np.hypot(x - pose[0], y - pose[1]) < 0.004
        found += 1
    assert found >= 8


def test_tick_without_new_frame_marks_nobody_seen_and_ages(setup) -> None:
    r, sim, _ = setup

    class OneShot:
        """A source that delivers a single frame and then nothing new."""

        def __init__(self) -> None:
            self.cam = SyntheticCamera(sim.poses, ids=range(10), renderer=r)
            self.done = False
            self.status = "one-shot"

        @property
        def ok(self) -> bool:
            return True

        def read(self, now: float):
            if self.done:
                return None
            self.done = True
            return self.cam.read(now)

        def close(self) -> None:
            pass

    src = CameraPoseSource(OneShot(), Tracker(TrackerConfig(calibration=CameraCalibration.from_camera(r.camera))))
    assert src.read(1.0).seen.all()
    tp = src.read(1.05)
    assert not tp.seen.any() and not tp.stale.any() and "no new frame" in tp.status
    tp = src.read(1.5)
    assert tp.stale.all() and np.all(tp.stamps == 1.0)


def test_open_synthetic_spec_wires_camera_tracker_and_expected_ids(setup, tmp_path) -> None:
    r, sim, _ = setup
    src = CameraPoseSource.open("synthetic", get_poses=lambda t: sim.poses(t)[:3], ids=[0, 1, 2],
                                config=TrackerConfig(expected_ids=(30,)))
    tp = src.read(0.0)
    assert tp.homography == "ok" and list(tp.ids) == [0, 1, 2, 30]
    assert tp.seen[:3].all() and np.max(np.hypot(*(tp.poses[:3, :2] - sim.poses(0.0)[:3, :2]).T)) < 0.003
    # robot 30 is expected (the simulator has it) but never seen: listed stale
    assert tp.stale[3] and not tp.seen[3] and "30 (never seen)" in tp.status
    # the tracker config (as written by `calibrate arena`) is accepted by path for other sources
    cfg_path = tmp_path / "arena.json"
    src.tracker.config.with_(expected_ids=()).save(cfg_path)
    folder = tmp_path / "imgs"
    folder.mkdir()
    cv2.imwrite(str(folder / "a.png"), src.source.read(0.1).image[..., ::-1])
    src.close()
    src3 = CameraPoseSource.open(str(folder), config=cfg_path, paced=False)
    assert src3.read(0.2).seen.sum() == 3
