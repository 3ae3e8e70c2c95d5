"""Recorded sources: a video file (paced with frame skipping, looped, or as fast as possible)
and an image folder go through the same tracker as the synthetic camera."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from swarmdeck.tracking import (
    CameraCalibration,
    CameraPoseSource,
    ImageFolderSource,
    SyntheticCameraConfig,
    SyntheticRenderer,
    Tracker,
    TrackerConfig,
    VideoFileSource,
    open_source,
    random_poses,
)

N_FRAMES = 6


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    """Six frames of robots moving +1 cm in x per frame, as an MJPG video and as PNG files."""
    r = SyntheticRenderer(SyntheticCameraConfig())
    base = random_poses(6, np.random.default_rng(8), margin=0.2)
    truth = [base + [0.01 * k, 0.0, 0.0] for k in range(N_FRAMES)]
    frames = [r.render(np.arange(6), p).image for p in truth]
    d = tmp_path_factory.mktemp("rec")
    video = d / "arena.avi"
    w = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (1280, 720))
    assert w.isOpened()
    for f in frames:
        w.write(f[..., ::-1])
    w.release()
    folder = d / "frames"
    folder.mkdir()
    for k, f in enumerate(frames):
        cv2.imwrite(str(folder / f"f{k:02d}.png"), f[..., ::-1])
    return r, truth, video, folder


def _x_of_robot0(r, frame) -> float:
    tr = Tracker(TrackerConfig(calibration=CameraCalibration.from_camera(r.camera)))
    tp = tr.update(frame)
    assert tp.seen.all(), tp.status
    return float(tp.poses[0, 0])


def test_video_as_fast_as_possible_returns_every_frame_then_loops(recording) -> None:
    r, truth, video, _ = recording
    src = VideoFileSource(video, paced=False)
    assert src.ok and "6 frames at 10 fps" in src.status
    idx = [src.read(0.0).index for _ in range(N_FRAMES + 2)]
    assert idx == list(range(N_FRAMES + 2))
    src.close()


def test_video_paced_skips_to_the_newest_frame(recording) -> None:
    r, truth, video, _ = recording
    src = VideoFileSource(video, paced=True)
    f0 = src.read(100.0)                       # first read starts the clock
    assert f0.index == 0 and f0.stamp == 100.0
    assert src.read(100.05) is None            # still frame 0 (10 fps): nothing new
    f = src.read(100.35)                       # frames 1 and 2 skipped
    assert f.index == 3
    assert abs(_x_of_robot0(r, f) - truth[3][0, 0]) < 0.004
    f = src.read(100.0 + 0.1 * (N_FRAMES + 1))   # looped: frame 1 of the second pass
    assert f.index == N_FRAMES + 1
    assert abs(_x_of_robot0(r, f) - truth[1][0, 0]) < 0.004
    src.close()


def test_image_folder_in_name_order_through_open_source(recording) -> None:
    r, truth, _, folder = recording
    src = open_source(str(folder), paced=False)
    assert isinstance(src, ImageFolderSource) and src.ok
    pose_src = CameraPoseSource(src, Tracker(TrackerConfig(calibration=CameraCalibration.from_camera(r.camera))))
    xs = [pose_src.read(0.1 * k).poses[0, 0] for k in range(N_FRAMES)]
    assert np.allclose(xs, [t[0, 0] for t in truth], atol=0.002)
    assert pose_src.health()["frames"] == N_FRAMES


def test_threaded_capture_hands_out_only_the_newest_frame(recording) -> None:
    """OpenCVCamera (the webcam path) on a stream that delivers faster than it is read: every
    read returns the newest frame, never the same frame twice, never an older one."""
    _, _, video, _ = recording
    from swarmdeck.tracking import OpenCVCamera

    cam = OpenCVCamera(str(video), retry_s=0.01)

    def wait_for(pred) -> bool:                 # bounded polling of the capture thread, no timing claims
        for _ in range(3000):
            if pred():
                return True
            cam._service.wait(0.01)
        return False

    try:
        assert wait_for(lambda: cam.frames_grabbed >= 3), cam.status
        f1 = cam.read(0.0)
        assert f1.index >= 2                               # the newest, not the first queued
        assert f1.image.shape == (720, 1280, 3) and f1.image.dtype == np.uint8
        f2 = cam.read(0.0)
        assert f2 is None or f2.index > f1.index           # never the same frame twice
        n = cam.frames_grabbed
        assert wait_for(lambda: cam.frames_grabbed >= n + 3), cam.status
        f3 = cam.read(0.0)
        assert f3.index >= n + 2                           # older frames were dropped, not queued
    finally:
        cam.close()
