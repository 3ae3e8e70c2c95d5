"""MP4 export: an H.264 video browsers play, one frame per 1/fps s of the recording, robots drawn where they were."""
from __future__ import annotations

import dataclasses
import math
import sys

import av
import numpy as np
import pytest

from swarmdeck.console.cli import main
from swarmdeck.console.recording.export_video import (
    VideoExportError,
    VideoLayout,
    VideoStyle,
    export_video,
    video_frame_count,
)
from swarmdeck.console.recording.foxglove import FoxgloveConfig
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
from swarmdeck.console.web.scene import robot_colors

W, H = 320, 200
GREEN = np.array([0, 200, 0], dtype=np.uint8)
CAMERA_FROM, ESTOP_FROM = 20, 30  # ticks (dt 0.05 s)


def _frames():
    """40 ticks of the console's real loop (6 robots, coverage); the e-stop pressed before tick 30;
    a camera picture (solid green) referenced from tick 20 on."""
    from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig

    now = [0.0]
    loop = ControlLoop(LoopConfig(n_robots=6, dt=0.05, seed=3, behaviour="coverage"), clock=lambda: now[0])
    try:
        for k in range(40):
            now[0] = 0.05 * k
            if k == ESTOP_FROM:
                loop.estop()
            f = loop.tick()
            yield dataclasses.replace(f, image_ref=f"img{k // 5}") if k >= CAMERA_FROM else f
    finally:
        loop.close()


def _picture(ref: str):
    img = np.zeros((60, 96, 3), dtype=np.uint8)
    img[:] = GREEN
    return img, (-1.6, 1.6, -1.0, 1.0)


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    path = tmp_path_factory.mktemp("video") / "run.mcap"
    with Recorder(path, config=RecorderConfig(chunk_frames=8), image_provider=_picture,
                  foxglove=FoxgloveConfig.per_entity()) as rec:  # the bytes spread evenly over the frames: a cut halves them
        for f in _frames():
            rec.write_frame(f)
    return path


@pytest.fixture(scope="module")
def video(recording, tmp_path_factory):
    out = tmp_path_factory.mktemp("mp4") / "run.mp4"
    calls = []
    with open_recording(recording) as rec:
        path, n = export_video(rec, out, VideoStyle(width=W, height=H, fps=10.0), progress=lambda d, t: calls.append((d, t)))
        duration = rec.duration
    with av.open(str(path)) as c:
        s = c.streams.video[0]
        info = (s.codec_context.name, s.codec_context.pix_fmt, s.width, s.height)
        images = [fr.to_ndarray(format="rgb24") for fr in c.decode(video=0)]
    return path, n, duration, info, images, calls


def test_the_video_is_h264_yuv420p_with_one_frame_per_tenth_of_a_second(video):
    path, n, duration, info, images, calls = video
    assert info == ("h264", "yuv420p", W, H)
    assert duration == pytest.approx(39 * 0.05, abs=1e-6)
    assert n == math.floor(duration * 10 + 1e-6) + 1 == len(images) == 20
    assert images[0].shape == (H, W, 3)
    assert calls[-1] == (n, n) and [d for d, _ in calls] == list(range(1, n + 1))
    assert not list(path.parent.glob(".*.part"))  # the temporary file was renamed


def _body_pixels(layout, frame):
    """Pixel (row, col) of a point inside each robot's body, behind its centre (the white heading tick
    and the id label are in front of / above it)."""
    p = frame.poses
    behind = p[:, :2] - 0.45 * 0.055 * np.column_stack((np.cos(p[:, 2]), np.sin(p[:, 2])))
    px = np.round(layout.to_px(behind)).astype(int)
    return px[:, 1], px[:, 0]


def test_every_robot_is_drawn_at_its_recorded_position_in_its_state_colour(recording, video):
    _, _, _, _, images, _ = video
    with open_recording(recording) as rec:
        layout = VideoLayout.fit(rec.first_frame.bounds, W, H, VideoStyle().camera_panel)  # it has pictures
        for k in (5, 12, 19):  # running (blue/orange), then e-stopped (red)
            _, frame = rec.frame_at(k / 10)
            rows, cols = _body_pixels(layout, frame)
            got = images[k][rows, cols].astype(int)
            want = robot_colors(frame).astype(int)
            assert np.abs(got - want).max() < 40, (k, got, want)
    assert frame.run_state == "estop" and (want == [210, 30, 30]).all()
    # somewhere the robots are not: the floor, not a robot colour
    assert np.abs(images[5][layout.top + 3, layout.left + 3].astype(int) - [20, 70, 170]).max() > 80


def test_the_camera_picture_appears_beside_the_arena_once_the_recording_has_one(recording, video):
    _, _, _, _, images, _ = video
    with open_recording(recording) as rec:
        layout = VideoLayout.fit(rec.first_frame.bounds, W, H, VideoStyle().camera_panel)
        assert len(list(rec.camera_pictures())) >= 1
    left, top, w, h = layout.panel
    assert left >= layout.left + layout.arena_w and w > 0  # never over a robot
    centre = (top + h // 2, left + w // 2)
    before, after = images[CAMERA_FROM // 2 - 1][centre], images[CAMERA_FROM // 2 + 1][centre]
    assert np.abs(after.astype(int) - GREEN).max() < 40
    assert np.abs(before.astype(int) - GREEN).max() > 80


def test_format_1_recordings_export_too(tmp_path):
    with open_recording("tests/data/recording_format1.mcap") as rec:
        assert rec.metadata["recording_format"] == 1
        path, n = export_video(rec, tmp_path / "old.mp4", VideoStyle(width=W, height=H, fps=20.0))
        assert n == video_frame_count(rec.duration, 20.0)
    with av.open(str(path)) as c:
        assert sum(1 for _ in c.decode(video=0)) == n


def test_a_failed_export_leaves_no_file(recording, tmp_path):
    out = tmp_path / "x.mp4"

    def stop(done, total):
        if done == 3:
            raise KeyboardInterrupt

    with open_recording(recording) as rec, pytest.raises(KeyboardInterrupt):
        export_video(rec, out, VideoStyle(width=W, height=H, fps=10.0), progress=stop)
    assert list(tmp_path.iterdir()) == []


def test_without_pyav_the_error_names_what_to_install(recording, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "av", None)  # import av now raises ImportError
    with open_recording(recording) as rec, pytest.raises(VideoExportError, match="PyAV.*pip install av"):
        export_video(rec, tmp_path / "x.mp4", VideoStyle(width=W, height=H))


def test_cli_video(recording, tmp_path, capsys):
    out = tmp_path / "cli.mp4"
    assert main(["export", str(recording), "--video", str(out), "--fps", "5", "--size", "240x160"]) == 0
    assert "wrote a 10-frame video" in capsys.readouterr().out
    with av.open(str(out)) as c:
        assert (c.streams.video[0].width, c.streams.video[0].height) == (240, 160)


@pytest.mark.parametrize("argv, message", [
    (["--size", "320"], "--size must look like 1280x720"),
    (["--size", "321x200"], "--size width must be an even number"),
    (["--fps", "0"], "--fps must be in (0, 120]"),
])
def test_cli_video_bad_options(recording, tmp_path, capsys, argv, message):
    assert main(["export", str(recording), "--video", str(tmp_path / "v.mp4"), *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_cli_video_of_a_bad_or_truncated_recording(recording, tmp_path, capsys):
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"this is not a recording" * 10)
    assert main(["export", str(junk), "--video", str(tmp_path / "a.mp4")]) == 2
    err = capsys.readouterr().err
    assert "not an MCAP file" in err and err.count("\n") == 1
    data = recording.read_bytes()
    head = tmp_path / "head.mcap"  # cut before the first chunk: nothing to draw
    head.write_bytes(data[:600])
    assert main(["export", str(head), "--video", str(tmp_path / "b.mp4")]) == 2
    err = capsys.readouterr().err
    assert "holds no readable frame" in err and err.count("\n") == 1
    assert not (tmp_path / "a.mp4").exists() and not (tmp_path / "b.mp4").exists()
    cut = tmp_path / "cut.mcap"  # a crash mid-recording: the readable part is exported, with a warning
    cut.write_bytes(data[:len(data) // 2])
    assert main(["export", str(cut), "--video", str(tmp_path / "c.mp4"), "--fps", "10", "--size", "160x100"]) == 0
    out = capsys.readouterr().out
    assert "warning: " in out and "wrote a " in out
    with open_recording(cut) as rec:
        n = video_frame_count(rec.duration, 10.0)
        assert 0.5 < rec.duration < 1.9
    with av.open(str(tmp_path / "c.mp4")) as c:
        assert sum(1 for _ in c.decode(video=0)) == n


def test_barrier_activity_is_drawn(recording):
    """An active pair (h ≤ 0: red line between the look-ahead points) and a robot the filter moved
    (orange body and an orange ring round it)."""
    from swarmdeck.console.recording.export_video import FrameRenderer
    from swarmdeck.console.runtime.frame import BarrierFrame

    with open_recording(recording) as rec:
        _, frame = rec.frame_at(0.5)
    n = frame.n
    inter = np.zeros(n)
    inter[2] = 0.05
    b = BarrierFrame(active_pairs=[[0, 1]], active_h=[0.0], intervention=inter, n_active=1, min_distance=0.2)
    frame = dataclasses.replace(frame, barrier=b)
    style = VideoStyle(width=640, height=400)
    layout = VideoLayout.fit(frame.bounds, 640, 400)
    img = FrameRenderer(layout, style).render(frame, 0.5)
    mid = layout.to_px(0.5 * (frame.points[0] + frame.points[1]))
    # the midpoint may fall on a robot body if the two are close; take a point a third of the way
    third = layout.to_px(frame.points[0] + (frame.points[1] - frame.points[0]) / 3)
    reds = [img[int(round(p[1])), int(round(p[0]))] for p in (mid, third)]
    assert any(abs(int(c[0]) - 230) < 20 and c[1] < 60 and c[2] < 40 for c in reds), reds
    ring = layout.to_px(frame.poses[2, :2] + [1.7 * style.robot_radius, 0.0])
    rows, cols = np.meshgrid(np.arange(-1, 2) + int(round(ring[1])), np.arange(-1, 2) + int(round(ring[0])))
    near = img[rows.ravel(), cols.ravel()].astype(int)
    assert (np.abs(near - [255, 140, 0]).max(axis=1) < 50).any()
    rows, cols = _body_pixels(layout, frame)
    assert np.abs(img[rows[2], cols[2]].astype(int) - [255, 140, 0]).max() < 10


def test_virtual_robots_are_pale_in_a_dashed_ring_as_in_the_console(recording):
    from swarmdeck.console.recording.export_video import FrameRenderer
    from swarmdeck.console.web.scene import VIRTUAL_RING

    with open_recording(recording) as rec:
        _, frame = rec.frame_at(0.5)
    virtual = np.zeros(frame.n, dtype=bool)
    virtual[1] = True
    frame = dataclasses.replace(frame, is_virtual=virtual)
    style = VideoStyle(width=640, height=400)
    layout = VideoLayout.fit(frame.bounds, 640, 400)
    img = FrameRenderer(layout, style).render(frame, 0.5)
    rows, cols = _body_pixels(layout, frame)
    want = robot_colors(frame).astype(int)
    assert np.abs(img[rows, cols].astype(int) - want).max() < 10 and (want[1] > want[0]).all()  # paler
    a = np.radians(11.25)  # the middle of the first dash
    on = layout.to_px(frame.poses[1, :2] + 1.35 * style.robot_radius * np.cos(np.radians(11.25)) *
                      np.array([np.cos(a), np.sin(a)]))
    near = img[int(round(on[1])) - 1:int(round(on[1])) + 2, int(round(on[0])) - 1:int(round(on[0])) + 2]
    assert (np.abs(near.reshape(-1, 3).astype(int) - VIRTUAL_RING).max(axis=1) < 40).any()
    gap = layout.to_px(frame.poses[0, :2] + 1.35 * style.robot_radius * np.array([np.cos(a), np.sin(a)]))
    assert np.abs(img[int(round(gap[1])), int(round(gap[0]))].astype(int) - VIRTUAL_RING).max() > 60  # robot 0: none
