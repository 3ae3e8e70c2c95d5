"""The communication graph is a switchable layer of the picture, and every renderer draws it the same: the viser
scene (live, playback), the MP4 video, the Foxglove channels and the portal's live view show the picture's links
in the picture's colours; ``PictureStyle(show_network=False)`` and the scene's layer switch hide it."""
from __future__ import annotations

import foxglove.messages as fm
import numpy as np
import pytest
import viser
from foxglove_schemas import decode

from swarmdeck.console.picture import PictureStyle, picture_of
from swarmdeck.console.picture.colours import LINK_BUSY, LINK_IDLE
from swarmdeck.console.portal.live import scene_message
from swarmdeck.console.recording.export_video import FrameRenderer, VideoLayout, VideoStyle
from swarmdeck.console.recording.foxglove import FoxgloveEncoder
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.network_frame import NetworkFrame
from swarmdeck.console.web.scene import ArenaScene

POSES = np.array([[-1.15, 0.3, 0.0], [-0.35, 0.3, 0.0], [0.35, -0.3, 0.5], [1.15, 0.65, 1.0]])
# 0 <-> 1 busy both ways (2 · 30 messages/s), 1 -> 2 idle, 2 -> 3 at 15 messages/s
LINKS = [[0, 1], [1, 0], [1, 2], [2, 3]]
RATE = [30.0, 30.0, 0.0, 15.0]


NETWORK = NetworkFrame(np.array(LINKS), np.array(RATE))


def _frame(network: NetworkFrame | None = NETWORK) -> Frame:
    n = len(POSES)
    return Frame(tick=3, time=0.1, poses=POSES, ids=np.arange(n), nominal=np.zeros((n, 2)), safe=np.zeros((n, 2)),
                 v=np.zeros(n), w=np.zeros(n), network=network)


def test_the_picture_has_one_segment_per_linked_pair_coloured_by_rate():
    layer = picture_of(_frame()).network
    assert layer is not None
    assert layer.pairs.tolist() == [[0, 1], [1, 2], [2, 3]] and layer.rate.tolist() == [60.0, 0.0, 15.0]
    assert tuple(layer.colors[0]) == LINK_BUSY and tuple(layer.colors[1]) == LINK_IDLE
    assert layer.busy.tolist() == [True, False, True]
    assert np.allclose(layer.segments[2], POSES[[2, 3], :2])
    assert picture_of(_frame(), PictureStyle(show_network=False)).network is None
    assert picture_of(_frame(None)).network is None
    with pytest.raises(ValueError, match="names robot 9"):
        _frame(NetworkFrame(np.array([[0, 9]]), np.array([1.0])))


def _expected() -> tuple[np.ndarray, list[tuple[int, ...]]]:
    layer = picture_of(_frame()).network
    assert layer is not None
    return layer.segments.reshape(-1, 4), [tuple(int(v) for v in c) for c in layer.colors]


@pytest.fixture(scope="module")
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


def test_the_viser_scene_draws_the_links_and_switches_them_off(server):
    segs, cols = _expected()
    server.scene.reset()
    scene = ArenaScene(server, bounds=_frame().bounds)
    scene.draw(_frame())
    node = scene.nodes.network
    assert node is not None and node.visible
    assert np.allclose(np.asarray(node.points)[:, :, :2].reshape(-1, 4), segs, atol=1e-6)
    assert [tuple(c) for c in np.asarray(node.colors)[:, 0].tolist()] == cols
    scene.set_layer("network", False)
    assert not node.visible
    scene.set_layer("network", True)
    scene.draw(_frame(None))
    assert np.asarray(node.points)[0, 0, 2] < 0  # nothing to draw: the hidden stub


def test_the_video_draws_the_links_in_the_pictures_colours():
    segs, cols = _expected()
    layout = VideoLayout.fit(_frame().bounds, 1280, 720)
    img = FrameRenderer(layout, VideoStyle()).render(_frame(), 0.0).astype(int)
    plain = FrameRenderer(layout, VideoStyle()).render(_frame(None), 0.0).astype(int)
    for seg, col in zip(segs, cols):
        c, r = np.round(layout.to_px(0.5 * (seg[:2] + seg[2:]))).astype(int)
        window = img[r - 2:r + 3, c - 2:c + 3].reshape(-1, 3)
        assert np.abs(window - np.array(col)).sum(axis=1).min() < 40, (col, window)
        assert (np.abs(plain[r - 2:r + 3, c - 2:c + 3].reshape(-1, 3) - np.array(col)).sum(axis=1) >= 40).all() \
            or col == LINK_IDLE  # without the network the floor there is not the link colour


def test_foxglove_and_the_live_view_draw_the_same_links():
    segs, cols = _expected()
    enc = FoxgloveEncoder(bounds=_frame().bounds)
    scene = decode("foxglove.SceneUpdate", fm.SceneUpdate.get_schema().data, enc.network(_frame(), 0))
    (line,) = scene.entities[0].lines
    xy = np.array([[q.x, q.y] for q in line.points]).reshape(-1, 4)
    assert np.allclose(xy, segs) and [tuple(round(255 * v) for v in (c.r, c.g, c.b)) for c in line.colors[::2]] == cols
    topics = [t for t, _, _ in FoxgloveEncoder(bounds=_frame().bounds).encode(_frame(), 0, 0.0)]
    assert "/foxglove/network" in topics
    assert "/foxglove/network" not in [t for t, _, _ in FoxgloveEncoder(bounds=_frame().bounds).encode(_frame(None), 0, 0.0)]
    m = scene_message(_frame(), 1)
    assert m["links"] == [[0, 1], [1, 2], [2, 3]]
    assert [tuple(int(m["link_colours"][k][i:i + 2], 16) for i in (1, 3, 5)) for k in range(3)] == cols
    assert scene_message(_frame(None), 1)["links"] == []
