"""Foxglove channels packed (``FoxgloveConfig(packed=True)``, ``[recording] packed = true``): the robots are
one ``foxglove.PointCloud`` on ``/foxglove/robot_points`` (x, y, z, yaw float32 + rgba uint8, 20 bytes a
robot) that decodes to the frame's poses and the picture's colours; ``/foxglove/robots`` keeps the arena
boundary; ``lines_period`` thins the Voronoi-edge and barrier scenes; packed and thinned is the default, one entity
per robot (``FoxgloveConfig.per_entity()``, ``--foxglove-entities``, ``packed = false``) stays selectable."""
from __future__ import annotations

import numpy as np
import pytest
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from mcap.reader import make_reader
from recording_synth import simulated_frames

from swarmdeck.console.picture.picture import robot_colors
from swarmdeck.console.recording.foxglove import (
    POINT_STRIDE,
    TOPIC_BARRIER,
    TOPIC_CELLS,
    TOPIC_POSES,
    TOPIC_ROBOT_POINTS,
    TOPIC_ROBOTS,
    FoxgloveConfig,
)
from swarmdeck.console.recording.recorder import Recorder
from swarmdeck.console.runtime.config import load_settings


def _decoder(schema):
    fds = descriptor_pb2.FileDescriptorSet.FromString(schema.data)
    pool = descriptor_pool.DescriptorPool()
    for fd in fds.file:
        pool.Add(fd)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name))


def _record(path, frames, config):
    with Recorder(path, foxglove=config) as rec:
        for f in frames:
            rec.write_frame(f)
    out: dict[str, list] = {}
    with open(path, "rb") as fh:
        for schema, channel, message in make_reader(fh).iter_messages():
            out.setdefault(channel.topic, []).append((schema, message))
    return out


@pytest.fixture(scope="module")
def frames():
    return list(simulated_frames(n_robots=7, n_ticks=30, dt=1 / 30))


def test_packed_robots_are_one_point_cloud_of_the_frame(tmp_path, frames):
    got = _record(tmp_path / "p.mcap", frames, FoxgloveConfig(packed=True))
    assert TOPIC_POSES not in got and len(got[TOPIC_ROBOT_POINTS]) == len(frames)
    schema, message = got[TOPIC_ROBOT_POINTS][-1]
    cloud = _decoder(schema).FromString(message.data)
    assert cloud.frame_id == "arena" and cloud.point_stride == POINT_STRIDE
    f = frames[-1]
    rec = np.frombuffer(cloud.data, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("yaw", "<f4"), ("rgba", "u1", 4)])
    assert len(rec) == f.n and [fl.name for fl in cloud.fields] == ["x", "y", "z", "yaw", "red", "green", "blue", "alpha"]
    assert np.array_equal(rec["x"], f.poses[:, 0].astype("<f4")) and np.array_equal(rec["y"], f.poses[:, 1].astype("<f4"))
    assert np.array_equal(rec["yaw"], f.poses[:, 2].astype("<f4"))
    assert np.array_equal(rec["rgba"][:, :3], robot_colors(f)) and (rec["rgba"][:, 3] == 255).all()
    schema, message = got[TOPIC_ROBOTS][-1]
    scene = _decoder(schema).FromString(message.data)
    assert [e.id for e in scene.entities] == ["arena"]


def test_lines_period_thins_cells_and_barrier(tmp_path, frames):
    got = _record(tmp_path / "l.mcap", frames, FoxgloveConfig(packed=True, lines_period=0.5))
    for topic in (TOPIC_CELLS, TOPIC_BARRIER):
        assert len(got[topic]) == 2, topic  # 1 s at 30 Hz: t = 0 and t = 0.5 s
    assert len(got[TOPIC_ROBOT_POINTS]) == len(frames)


def test_the_default_is_packed_and_thinned_and_per_entity_stays_selectable(tmp_path, frames):
    got = _record(tmp_path / "d.mcap", frames, None)  # 7 robots: every frame (robot_rate 1000), lines every 1 s
    assert TOPIC_POSES not in got and len(got[TOPIC_ROBOT_POINTS]) == len(frames) and len(got[TOPIC_CELLS]) == 1
    assert FoxgloveConfig() == FoxgloveConfig(packed=True, robot_rate=1000.0, lines_period=1.0)
    got = _record(tmp_path / "e.mcap", frames, FoxgloveConfig.per_entity())
    assert TOPIC_ROBOT_POINTS not in got and len(got[TOPIC_POSES]) == len(got[TOPIC_CELLS]) == len(frames)


def test_the_config_file_packs(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text("[recording]\npacked = true\nlines_period = 0.5\n")
    s = load_settings(p)
    assert s.packed is True and s.lines_period == 0.5
    with pytest.raises(ValueError, match="lines_period"):
        FoxgloveConfig(lines_period=-1.0)
