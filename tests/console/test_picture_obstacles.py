"""Line-segment obstacles in the picture and every renderer: the viser scene (live, playback, HTML), the MP4
video, the Foxglove channels and the portal's live view draw the Frame's obstacles, in the picture's colour,
where they are; a Frame without obstacles draws none."""
from __future__ import annotations

import foxglove.messages as fm
import numpy as np
import pytest
import viser
from foxglove_schemas import decode

from swarmdeck.console.picture import picture_of
from swarmdeck.console.picture.colours import OBSTACLE, hex_colors
from swarmdeck.console.portal.live import scene_message
from swarmdeck.console.recording.export_video import FrameRenderer, VideoLayout, VideoStyle
from swarmdeck.console.recording.foxglove import FoxgloveEncoder
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.web.scene import ArenaScene
from swarmdeck.core.obstacles import Obstacles

OBS = Obstacles.from_polygons([[[0.2, -0.7], [0.9, -0.7], [0.9, -0.2]]], segments=[[[-1.2, 0.7], [-0.3, 0.7]]])
POSES = np.array([[-1.0, -0.5, 0.0], [0.0, 0.2, 1.0]])


def _frame(obstacles: Obstacles | None) -> Frame:
    n = len(POSES)
    return Frame(tick=1, time=0.033, poses=POSES, ids=np.arange(n), nominal=np.zeros((n, 2)), safe=np.zeros((n, 2)),
                 v=np.zeros(n), w=np.zeros(n), obstacles=obstacles)


@pytest.fixture(scope="module")
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


def test_picture_carries_the_frames_obstacles() -> None:
    np.testing.assert_array_equal(picture_of(_frame(OBS)).obstacles, OBS.segments)
    assert picture_of(_frame(None)).obstacles.shape == (0, 2, 2)


def test_viser_scene_draws_them_once_as_a_layer(server) -> None:
    server.scene.reset()
    scene = ArenaScene(server)
    scene.draw(_frame(OBS))
    node = scene.nodes.obstacles
    assert node is not None
    np.testing.assert_allclose(np.asarray(node.points)[:, :, :2], OBS.segments, atol=1e-6)
    scene.draw(_frame(OBS))
    assert scene.nodes.obstacles is node  # static: not redrawn while unchanged
    scene.set_layer("obstacles", False)
    assert node.visible is False
    scene.draw(_frame(None))
    assert scene.nodes.obstacles is None


def test_video_draws_them_in_the_obstacle_colour() -> None:
    layout = VideoLayout.fit(_frame(OBS).bounds, 1280, 720)
    for obstacles, want in ((OBS, True), (None, False)):
        img = FrameRenderer(layout, VideoStyle()).render(_frame(obstacles), 0.0)
        mids = 0.5 * (OBS.segments[:, 0] + OBS.segments[:, 1])
        px = np.round(layout.to_px(mids)).astype(int)
        hit = [np.abs(img[r, c].astype(int) - np.array(OBSTACLE)).sum() < 30 for c, r in px]
        assert all(hit) if want else not any(hit)


def test_foxglove_arena_entity_holds_them() -> None:
    enc = FoxgloveEncoder(bounds=_frame(OBS).bounds)
    for data in (enc.robots(_frame(OBS), 0), enc.arena(0, _frame(OBS))):
        scene = decode("foxglove.SceneUpdate", fm.SceneUpdate.get_schema().data, data)
        arena = [e for e in scene.entities if e.id == "arena"][0]
        assert len(arena.lines) == 2
        xy = np.array([[q.x, q.y] for q in arena.lines[1].points]).reshape(-1, 2, 2)
        np.testing.assert_allclose(xy, OBS.segments, atol=1e-9)
    scene = decode("foxglove.SceneUpdate", fm.SceneUpdate.get_schema().data, enc.robots(_frame(None), 0))
    assert len([e for e in scene.entities if e.id == "arena"][0].lines) == 1


def test_portal_live_view_sends_them_with_their_colour() -> None:
    m = scene_message(_frame(OBS), 1)
    np.testing.assert_allclose(m["obstacles"], OBS.segments, atol=1e-4)
    assert m["palette"]["obstacle"] == hex_colors(np.array([OBSTACLE], dtype=np.uint8))[0]
    assert scene_message(_frame(None), 2)["obstacles"] == []
