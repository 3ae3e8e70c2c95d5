"""What an experiment drew appears in every renderer of the picture (issue 29 item 3): the viser scene (live,
playback, HTML), the MP4 video, the Foxglove channel and the portal's live view JSON all draw the Frame's
annotations — the same shapes, at the same places, in the same colours."""
from __future__ import annotations

import foxglove.messages as fm
import numpy as np
import pytest
import viser
from foxglove_schemas import decode

from swarmdeck.console.picture import picture_of
from swarmdeck.console.picture.annotations import annotation_segments, filled_polygons
from swarmdeck.console.portal.live import scene_message
from swarmdeck.console.recording.export_video import FrameRenderer, VideoLayout, VideoStyle
from swarmdeck.console.recording.foxglove import FoxgloveEncoder
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.web.scene import ArenaScene
from swarmdeck.core.annotations import CIRCLE, POINT, POLYGON, POLYLINE, TEXT, Annotations

# a filled red square, a green ring, a translucent blue dot, a magenta polyline, a caption; robots far from them
ANN = Annotations(kinds=[POLYGON, CIRCLE, POINT, POLYLINE, TEXT], offsets=[0, 4, 5, 6, 9, 10],
                  vertices=[[-1.3, -0.8], [-0.9, -0.8], [-0.9, -0.4], [-1.3, -0.4], [0.8, -0.5], [0.2, 0.6],
                            [-0.5, 0.2], [0.0, 0.25], [0.5, 0.2], [1.0, 0.7]],
                  sizes=[0.01, 0.2, 0.05, 0.02, 0.1],
                  colors=[[220, 20, 20, 255], [20, 180, 20, 255], [20, 20, 220, 128], [200, 0, 200, 255], [0, 0, 0, 255]],
                  filled=[True, False, True, False, False], texts=("", "", "", "", "hello"))
FRAME = Frame(tick=1, time=0.033, poses=np.array([[1.3, -0.8, 0.0], [-1.3, 0.8, 0.0]]), ids=np.arange(2),
              nominal=np.zeros((2, 2)), safe=np.zeros((2, 2)), v=np.zeros(2), w=np.zeros(2), annotations=ANN)


def test_the_picture_carries_them_and_splits_them_for_line_renderers():
    pic = picture_of(FRAME)
    assert pic.annotations is ANN
    segs, cols, _ = annotation_segments(ANN)
    assert len(segs) == 2 + 32  # the polyline's 2 segments, the ring's 32; the filled square is not an outline
    assert cols[:2].tolist() == [[200, 0, 200, 255]] * 2
    polys, pcols = filled_polygons(ANN)
    assert len(polys) == 2 and pcols[:, :3].tolist() == [[220, 20, 20], [20, 20, 220]]
    assert picture_of(Frame(tick=0, time=0.0, poses=np.zeros((0, 3)), ids=[], nominal=np.zeros((0, 2)),
                            safe=np.zeros((0, 2)), v=[], w=[])).annotations.kinds.size == 0


def test_the_video_draws_them():
    layout = VideoLayout.fit(FRAME.bounds, 1280, 720)
    img = FrameRenderer(layout, VideoStyle()).render(FRAME, 0.0)

    def at(x, y):
        c, r = np.round(layout.to_px(np.array([x, y]))).astype(int)
        return img[r, c].astype(int)

    assert at(-1.1, -0.6).tolist() == [220, 20, 20]  # inside the filled square
    assert at(0.8 + 0.2, -0.5).tolist() == pytest.approx([20, 180, 20], abs=40)  # on the ring
    centre = at(0.8, -0.5)
    assert abs(int(centre[1]) - int(centre[0])) < 20  # the ring's centre is the floor, not filled green
    blended = at(0.2, 0.6)  # the translucent dot: blue blended half over the floor
    assert blended[2] > blended[0] + 50 and blended[0] > 60
    assert at(0.0, 0.25).tolist() == pytest.approx([200, 0, 200], abs=40)  # on the polyline
    c, r = np.round(layout.to_px(np.array([1.0, 0.7]))).astype(int)
    assert (img[r - 15:r + 15, c - 40:c + 40].sum(axis=2) < 100).sum() > 20  # dark caption pixels round its anchor


def test_foxglove_draws_them_as_one_entity():
    enc = FoxgloveEncoder(bounds=FRAME.bounds)
    scene = decode("foxglove.SceneUpdate", fm.SceneUpdate.get_schema().data, enc.annotations(FRAME, 0))
    (entity,) = scene.entities
    assert entity.id == "annotations"
    (lines,) = entity.lines
    assert len(lines.points) == 2 * (2 + 32)
    assert round(lines.colors[0].r * 255) == 200 and round(lines.colors[0].b * 255) == 200
    (triangles,) = entity.triangles
    assert len(triangles.points) == 3 * 2  # the square (2 triangles)
    (dot,) = entity.spheres  # the translucent dot
    assert (dot.pose.position.x, dot.size.x, round(dot.color.a, 2)) == (0.2, 0.1, 0.5)
    assert [t.text for t in entity.texts] == ["hello"]
    assert (entity.texts[0].pose.position.x, entity.texts[0].pose.position.y) == (1.0, 0.7)
    empty = decode("foxglove.SceneUpdate", fm.SceneUpdate.get_schema().data,
                   enc.annotations(Frame(tick=0, time=0.0, poses=np.zeros((0, 3)), ids=[], nominal=np.zeros((0, 2)),
                                         safe=np.zeros((0, 2)), v=[], w=[]), 0))
    assert not empty.entities[0].lines and not empty.entities[0].texts  # nothing drawn: an empty entity replaces


def test_the_live_view_json_carries_them():
    m = scene_message(FRAME, 1)
    a = m["annotations"]
    assert a["kinds"] == ANN.kinds.tolist() and a["offsets"] == ANN.offsets.tolist()
    assert a["vertices"] == ANN.vertices.tolist() and a["texts"][4] == "hello"
    assert a["colours"][2] == "rgba(20,20,220,0.502)"
    assert "annotations" not in scene_message(Frame(tick=0, time=0.0, poses=np.zeros((1, 3)), ids=[0],
                                                    nominal=np.zeros((1, 2)), safe=np.zeros((1, 2)), v=[0.0], w=[0.0]), 2)


def test_the_viser_scene_draws_them():
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        scene = ArenaScene(server, bounds=FRAME.bounds)
        scene.draw(FRAME)
        nodes = scene.nodes.annotations
        segs = np.asarray(nodes.lines.points)
        assert segs.shape == (34, 2, 3)
        np.testing.assert_allclose(segs[0, :, :2], [[-0.5, 0.2], [0.0, 0.25]], atol=1e-6)
        assert np.asarray(nodes.lines.colors)[0, 0].tolist() == [200, 0, 200]
        np.testing.assert_allclose(np.asarray(nodes.points.points)[:, :2], [[0.2, 0.6]], atol=1e-6)
        assert [lab.text for lab in nodes.labels if lab.visible] == ["hello"]
        scene.set_layer("annotations", False)
        assert not nodes.lines.visible and not any(lab.visible for lab in nodes.labels)
        scene.set_layer("annotations", True)
        scene.draw(Frame(tick=2, time=0.066, poses=FRAME.poses, ids=FRAME.ids, nominal=FRAME.nominal, safe=FRAME.safe,
                         v=FRAME.v, w=FRAME.w))  # nothing drawn any more: the layer empties
        assert np.asarray(nodes.lines.points)[0, 0, 2] < 0 and not any(lab.visible for lab in nodes.labels)
    finally:
        server.stop()


def test_a_recording_from_elsewhere_cannot_make_a_renderer_draw_a_million_primitives():
    n = 1_000_000  # a crafted file: the Frame holds them (it is data), the picture keeps the caps
    hostile = Annotations(kinds=np.zeros(n, dtype=np.uint8), offsets=np.arange(n + 1), vertices=np.full((n, 2), 9.0),
                          sizes=np.full(n, 0.01), colors=np.zeros((n, 4), dtype=np.uint8), filled=np.ones(n, dtype=bool),
                          texts=("",) * n)
    frame = Frame(tick=0, time=0.0, poses=np.zeros((0, 3)), ids=[], nominal=np.zeros((0, 2)), safe=np.zeros((0, 2)),
                  v=[], w=[], annotations=hostile)
    pic = picture_of(frame)
    assert len(pic.annotations) == 4096 and pic.annotations.vertices.max() == 1.6  # capped and clipped
    assert len(scene_message(frame, 1)["annotations"]["kinds"]) == 4096
