"""The sensors' layer (issue 28.1) in the picture and every renderer: ToF rays from sensor to end point (readings of
−1 and NaN draw nothing) and the LED colours, the same in the picture, the viser scene, the video, the Foxglove
channel and the portal's live view; ``PictureStyle(sensors=False)`` switches it off; Frames without sensors draw none."""
from __future__ import annotations

import dataclasses

import foxglove.messages as fm
import numpy as np
import pytest
import viser
from foxglove_schemas import decode

from swarmdeck.console.picture import PictureStyle, picture_of
from swarmdeck.console.picture.colours import SENSOR_HIT
from swarmdeck.console.portal.live import scene_message
from swarmdeck.console.recording.export_video import FrameRenderer, VideoLayout, VideoStyle
from swarmdeck.console.recording.foxglove import FoxgloveEncoder
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.sensors_frame import SensorsFrame
from swarmdeck.console.web.scene import ArenaScene
from swarmdeck.core.constants import TOF_BODY_OFFSET, TOF_SENSOR_POSES

POSES = np.array([[-1.0, 0.0, 0.0], [0.5, 0.4, np.pi / 2]])
FRONT = 3


def _frame(with_sensors: bool = True) -> Frame:
    n, k = len(POSES), len(TOF_SENSOR_POSES)
    d = np.full((n, k), -1.0)
    d[0, FRONT] = 0.4  # robot 0 reads 0.4 m ahead; robot 1 nothing yet (NaN) on one sensor, −1 elsewhere
    d[1, 0] = np.nan
    leds = np.array([[255, 0, 0], [0, 0, 0]])
    sensors = SensorsFrame(sensor_poses=np.array(TOF_SENSOR_POSES), body_offset=TOF_BODY_OFFSET, distances=d, leds=leds)
    return Frame(tick=1, time=0.033, poses=POSES, ids=np.arange(n), nominal=np.zeros((n, 2)), safe=np.zeros((n, 2)),
                 v=np.zeros(n), w=np.zeros(n), sensors=sensors if with_sensors else None)


START = np.array([-1.0 + TOF_BODY_OFFSET + 0.05, 0.0])
END = START + [0.4, 0.0]


def test_the_picture_has_one_ray_per_reading_and_the_leds():
    layer = picture_of(_frame()).sensors
    assert layer is not None
    np.testing.assert_allclose(layer.ray_starts, [START])
    np.testing.assert_allclose(layer.ray_ends, [END])
    assert layer.ray_robot.tolist() == [0]
    assert layer.leds.tolist() == [[255, 0, 0], [0, 0, 0]] and layer.led_on.tolist() == [True, False]
    assert picture_of(_frame(), PictureStyle(sensors=False)).sensors is None
    assert picture_of(_frame(with_sensors=False)).sensors is None


def test_the_live_view_sends_the_same_rays_and_leds():
    m = scene_message(_frame(), 1)
    np.testing.assert_allclose(m["sensors"]["rays"], [[START, END]], atol=1e-3)
    assert m["sensors"]["leds"] == ["#ff0000", None]
    assert "sensors" not in scene_message(_frame(with_sensors=False), 1)


def test_foxglove_gets_the_rays_on_its_sensors_channel():
    enc = FoxgloveEncoder()
    data = enc.sensors(_frame(), 0)
    msg = decode("foxglove.SceneUpdate", fm.SceneUpdate.get_schema().data, data)
    (entity,) = msg.entities
    pts = [(p.x, p.y) for p in entity.lines[0].points]
    np.testing.assert_allclose(pts, [START, END])
    assert len(entity.spheres) == 1 and len(entity.cylinders) == 1
    topics = [t for t, _, _ in enc.encode(_frame(), 0, 0.0)]
    assert "/foxglove/sensors" in topics
    assert "/foxglove/sensors" not in [t for t, _, _ in FoxgloveEncoder().encode(_frame(with_sensors=False), 0, 0.0)]


def test_the_video_draws_the_end_point():
    layout = VideoLayout.fit(_frame().bounds, 1280, 720)
    img = FrameRenderer(layout, VideoStyle()).render(_frame(), 0.0)
    c, r = np.round(layout.to_px(END[None])[0]).astype(int)
    assert tuple(int(v) for v in img[r, c]) == SENSOR_HIT
    off = FrameRenderer(layout, VideoStyle(), PictureStyle(sensors=False)).render(_frame(), 0.0)
    assert tuple(int(v) for v in off[r, c]) != SENSOR_HIT


@pytest.fixture(scope="module")
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


def test_the_viser_scene_draws_the_rays_and_can_hide_them(server):
    server.scene.reset()
    scene = ArenaScene(server, bounds=_frame().bounds)
    scene.draw(_frame())
    segs = np.asarray(scene.nodes.sensors.points)
    np.testing.assert_allclose(segs[:, :, :2].reshape(-1, 2), [START, END], atol=1e-6)
    assert np.asarray(scene.nodes.leds.colors).reshape(-1, 3).tolist()[0] == [255, 0, 0]
    scene.set_layer("sensors", False)
    assert not scene.nodes.sensors.visible and not scene.nodes.leds.visible
    scene.draw(dataclasses.replace(_frame(), tick=2))
