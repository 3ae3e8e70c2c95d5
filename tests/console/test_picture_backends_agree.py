"""The four renderers of a Frame agree by construction: the viser scene (live, playback, HTML), the MP4 video,
the Foxglove channels and the portal's live view show the same robot colours, the same active pairs in the
same colours and the same changed robots as the renderer-neutral picture (``swarmdeck.console.picture``)."""
from __future__ import annotations

import json

import foxglove.messages as fm
import numpy as np
import pytest
import viser
from foxglove_schemas import decode

from swarmdeck.console.picture import PictureStyle, picture_of
from swarmdeck.console.picture.colours import CHANGED
from swarmdeck.console.picture.shapes import CHANGED_RING
from swarmdeck.console.portal.live import scene_message
from swarmdeck.console.recording.export_video import FrameRenderer, VideoLayout, VideoStyle
from swarmdeck.console.recording.foxglove import FoxgloveEncoder
from swarmdeck.console.runtime.frame import BarrierFrame, Frame
from swarmdeck.console.web.scene import ArenaScene
from swarmdeck.core.constants import ROBOT_RADIUS

# five robots well apart (off the 0.5 m floor grid): 1 changed by the barrier, 2 unseen, 3 virtual; two active
# pairs, at h on the video's quantisation grid (red at h <= 0, yellow at h >= 0.1)
POSES = np.array([[-1.15, 0.3, 0.0], [-0.75, 0.3, 0.0], [0.15, -0.3, 0.5], [0.55, -0.3, 0.0], [1.15, 0.65, 1.0]])


def _frame(pairs: list[list[int]], h: list[float], run_state: str = "running") -> Frame:
    n = len(POSES)
    inter = np.zeros(n)
    inter[1] = 0.05
    inter[4] = 0.0009  # under the 1 mm/s threshold: not changed
    return Frame(tick=3, time=0.1, poses=POSES, ids=np.arange(10, 10 + n), nominal=np.zeros((n, 2)),
                 safe=np.zeros((n, 2)), v=np.zeros(n), w=np.zeros(n), run_state=run_state,
                 seen=np.array([True, True, False, True, True]), is_virtual=np.array([False, False, False, True, False]),
                 barrier=BarrierFrame(active_pairs=pairs, active_h=h, intervention=inter, n_active=len(pairs)))


FRAMES = {
    "two pairs": _frame([[0, 1], [2, 3]], [-0.01, 0.1]),
    "a pair naming a robot the frame lacks": _frame([[0, 1], [2, 7]], [-0.01, 0.1]),
    "paused": _frame([[0, 1]], [0.04], run_state="paused"),
}


@pytest.fixture(scope="module")
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


def _rgb(colour: str) -> tuple[int, ...]:
    return tuple(int(colour[k:k + 2], 16) for k in (1, 3, 5))


def _scene(server: viser.ViserServer, frame: Frame) -> dict:
    server.scene.reset()
    scene = ArenaScene(server, bounds=frame.bounds)
    scene.draw(frame)
    segs = np.asarray(scene.nodes.barrier.points)
    drawn = np.zeros((0, 4)) if segs[0, 0, 2] < 0 else segs[:, :, :2].reshape(-1, 4).astype(float)
    cols = np.asarray(scene.nodes.barrier.colors)
    return {"colours": [tuple(c) for c in np.asarray(scene.nodes.robots.batched_colors).tolist()],
            "segments": drawn, "pair_colours": [tuple(c) for c in cols[:, 0].tolist()] if len(drawn) else []}


def _video(frame: Frame) -> dict:
    layout = VideoLayout.fit(frame.bounds, 1280, 720)
    img = FrameRenderer(layout, VideoStyle()).render(frame, 0.0)
    p = frame.poses
    back = p[:, :2] - 0.5 * ROBOT_RADIUS * np.column_stack((np.cos(p[:, 2]), np.sin(p[:, 2])))  # inside the body
    px = np.round(layout.to_px(back)).astype(int)
    pts = frame.points
    colours, segments, pair_colours = [], [], []
    for i, j in ((a, b) for a in range(frame.n) for b in range(a + 1, frame.n)):
        c, r = np.round(layout.to_px(0.5 * (pts[i] + pts[j]))).astype(int)
        rgb = tuple(int(v) for v in img[r, c])
        if rgb[0] == 230:  # the pair ramp's red channel: a pair line through the midpoint
            segments.append(np.concatenate((pts[i], pts[j])))
            pair_colours.append(rgb)
    # the orange ring round a changed robot: pixels of the annulus (1.55 … 1.85 radii) in the changed colour
    yy, xx = np.mgrid[0:img.shape[0], 0:img.shape[1]]
    ring = []
    for k in range(frame.n):
        c, r = layout.to_px(p[k, :2])
        d = np.hypot(xx - c, yy - r) / (layout.scale * ROBOT_RADIUS)
        near = (d > CHANGED_RING - 0.15) & (d < CHANGED_RING + 0.15)
        ring.append(bool(np.any(np.abs(img[near].astype(int) - CHANGED.astype(int)).sum(axis=1) < 30)))
    colours = [tuple(int(v) for v in img[r, c]) for c, r in px]
    return {"colours": colours, "segments": np.array(segments).reshape(-1, 4), "pair_colours": pair_colours,
            "changed": ring}


def _foxglove(frame: Frame) -> dict:
    enc = FoxgloveEncoder(bounds=frame.bounds)
    robots = decode("foxglove.SceneUpdate", fm.SceneUpdate.get_schema().data, enc.robots(frame, 0))
    cyl = [e for e in robots.entities if e.id == "robots"][0].cylinders
    barrier = decode("foxglove.SceneUpdate", fm.SceneUpdate.get_schema().data, enc.barrier(frame, 0))
    lines = barrier.entities[0].lines
    segments, pair_colours = [], []
    for ln in lines:
        xy = np.array([[q.x, q.y] for q in ln.points]).reshape(-1, 4)
        segments += list(xy)
        pair_colours += [tuple(round(255 * v) for v in (c.r, c.g, c.b)) for c in ln.colors[::2]]
    metrics = json.loads(enc.metrics(frame, 0.0))
    return {"colours": [tuple(round(255 * v) for v in (c.color.r, c.color.g, c.color.b)) for c in cyl],
            "segments": np.array(segments).reshape(-1, 4), "pair_colours": pair_colours,
            "n_changed": metrics["robots_changed"]}


def _live(frame: Frame) -> dict:
    m = scene_message(frame, 1)
    pts = np.array(m["points"])
    return {"colours": [_rgb(c) for c in m["colours"]],
            "segments": np.array([np.concatenate((pts[i], pts[j])) for i, j in m["pairs"]]).reshape(-1, 4),
            "pair_colours": [_rgb(c) for c in m["pair_colours"]], "moved": m["moved"]}


@pytest.mark.parametrize("name", list(FRAMES))
def test_scene_video_foxglove_and_live_view_draw_the_same_picture(server, name: str) -> None:
    frame = FRAMES[name]
    pic = picture_of(frame, PictureStyle())
    colours = [tuple(c) for c in pic.colors.tolist()]
    pts = pic.points
    segments = np.array([np.concatenate((pts[i], pts[j])) for i, j in pic.pairs]).reshape(-1, 4)
    pair_colours = [tuple(c) for c in pic.pair_colors.tolist()]
    changed = pic.changed.tolist()
    assert changed == [False, True, False, False, False]
    assert len(set(colours)) >= 3  # the frame shows several states: the comparison means something

    scene, video, fox, live = _scene(server, frame), _video(frame), _foxglove(frame), _live(frame)
    for got in (scene, video, fox, live):
        assert got["colours"] == colours
    for got in (scene, video, fox, live):  # float32 in viser, 0.1 mm in the live view's JSON
        assert got["segments"].shape == segments.shape and got["pair_colours"] == pair_colours
        np.testing.assert_allclose(got["segments"], segments, atol=1e-4)
    assert video["changed"] == changed and fox["n_changed"] == sum(changed) and live["moved"] == [1]
    if name == "a pair naming a robot the frame lacks":
        assert len(segments) == 0  # the guard: no pair rather than a wrong one, in every backend


@pytest.mark.parametrize("name", list(FRAMES))
def test_the_projector_draws_the_same_robot_colours_and_safety_discs(name: str) -> None:
    from swarmdeck.console.projector.message import projector_message
    from swarmdeck.console.runtime.params import ProjectorParams

    frame = FRAMES[name]
    pic = picture_of(frame, PictureStyle())
    m = projector_message(frame, 1, ProjectorParams(safety=True), 0.0)
    halos = m["halos"]
    assert [_rgb(halos["palette"][k]) for k in halos["colour"]] == [tuple(c) for c in pic.colors.tolist()]
    np.testing.assert_allclose(m["halos"]["xy"], pic.poses[:, :2], atol=1e-3)
    np.testing.assert_allclose(m["safety"]["xy"], pic.points, atol=1e-3)
    assert m["safety"]["radius"] == pic.ring_radius
