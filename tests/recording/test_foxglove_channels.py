"""Foxglove-native channels in every recording: each message conforms to the official foxglove-sdk schema, carries
what the Frame says, and the shipped layout refers only to topics a recording has."""
from __future__ import annotations

import dataclasses
import json
import math
from importlib.resources import files

import cv2
import foxglove.messages as fm
import jsonschema
import numpy as np
import pytest
from foxglove_schemas import decode
from mcap.reader import make_reader

from swarmdeck.console.cli import main as cli
from swarmdeck.console.recording.foxglove import (
    METRICS_SCHEMA,
    PACKED_TOPICS,
    TOPIC_BARRIER,
    TOPIC_CAMERA,
    TOPIC_CELLS,
    TOPIC_CONTACTS,
    TOPIC_DENSITY,
    TOPIC_LOG,
    TOPIC_METRICS,
    TOPIC_POSES,
    TOPIC_ROBOTS,
    TOPIC_TF,
    TOPICS,
    FoxgloveConfig,
)
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder
from swarmdeck.console.recording.schemas import CHANNELS, TOPIC_FRAME
from swarmdeck.console.runtime.frame import BarrierFrame, ContactsFrame
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.web.scene import CHANGED, ROBOT


def _image(ref: str):
    """A synthetic overhead picture: a gradient (H, W, 3) RGB, row 0 at y_max."""
    k = int(ref.split(":")[1])
    img = np.zeros((60, 96, 3), dtype=np.uint8)
    img[..., 0] = np.linspace(0, 255, 96)[None, :]
    img[..., 1] = (40 * k) % 256
    return img, (-1.6, 1.6, -1.0, 1.0)


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    """A recording of real loop Frames, the later ones with barrier pairs, contacts, events, alerts and a camera."""
    loop = ControlLoop(LoopConfig(n_robots=12, seed=1))
    frames = [loop.tick() for _ in range(8)]
    n = frames[0].n
    extra = []
    for k, f in enumerate(frames[-4:]):
        inter = np.zeros(n)
        inter[[0, 1]] = 0.05
        extra.append(dataclasses.replace(
            f, tick=f.tick + 4, time=f.time + 4 * f.dt, image_ref=f"camera:{k}",
            barrier=BarrierFrame(active_pairs=[[0, 1], [2, 5]], active_h=[-0.001, 0.05], intervention=inter,
                                 min_distance=0.16, min_wall_clearance=0.3, n_active=2, solve_time_s=0.002),
            contacts=ContactsFrame(sources=("tuio:a",), ids=[3], positions=[[0.2, -0.1]], velocities=[[0, 0]]),
            events=(f"event {k}",), alerts=("script failing",) if k < 2 else ()))
    frames += extra
    path = tmp_path_factory.mktemp("fox") / "s.mcap"
    with Recorder(path, {"config": {"test": 1}}, image_provider=_image, foxglove=FoxgloveConfig.per_entity()) as rec:
        for f in frames:
            rec.write_frame(f)
        rec.write_event(frames[-1].time, "operator", "e-stop")
    by_topic: dict[str, list] = {}
    with open(path, "rb") as fh:
        for schema, channel, msg in make_reader(fh).iter_messages():
            by_topic.setdefault(channel.topic, []).append((schema, msg))
    return path, frames, by_topic


def test_every_foxglove_channel_uses_the_sdk_schema_and_its_messages_conform(session):
    _, frames, by_topic = session
    assert set(TOPICS) <= set(by_topic), f"missing: {set(TOPICS) - set(by_topic)}"
    for topic, cls in TOPICS.items():
        for schema, msg in by_topic[topic]:
            if cls is None:
                assert schema.encoding == "jsonschema"
                jsonschema.validate(json.loads(msg.data), json.loads(schema.data))
                continue
            official = getattr(fm, cls).get_schema()
            assert (schema.name, schema.encoding, schema.data) == (official.name, official.encoding,
                                                                   bytes(official.data))
            decode(schema.name, schema.data, msg.data)
    per_frame = [TOPIC_ROBOTS, TOPIC_CELLS, TOPIC_BARRIER, TOPIC_CONTACTS, TOPIC_POSES, TOPIC_TF, TOPIC_METRICS]
    for topic in per_frame:
        assert len(by_topic[topic]) == len(frames) == len(by_topic[TOPIC_FRAME])


def _decoded(by_topic, topic, i):
    schema, msg = by_topic[topic][i]
    return decode(schema.name, schema.data, msg.data), msg


def test_robots_scene_is_the_frame(session):
    _, frames, by_topic = session
    f = frames[-1]
    upd, msg = _decoded(by_topic, TOPIC_ROBOTS, len(frames) - 1)
    ents = {e.id: e for e in upd.entities}
    robots = ents["robots"]
    assert robots.frame_id == "arena"
    assert robots.timestamp.seconds * 10**9 + robots.timestamp.nanos == msg.log_time
    assert len(robots.cylinders) == len(robots.arrows) == len(robots.texts) == f.n
    xy = np.array([[c.pose.position.x, c.pose.position.y] for c in robots.cylinders])
    assert np.allclose(xy, f.poses[:, :2])
    yaw = np.array([2 * math.atan2(c.pose.orientation.z, c.pose.orientation.w) for c in robots.cylinders])
    assert np.allclose(np.angle(np.exp(1j * (yaw - f.poses[:, 2]))), 0, atol=1e-9)
    assert [t.text for t in robots.texts] == [str(i) for i in f.ids]
    rgb = np.array([[c.color.r, c.color.g, c.color.b] for c in robots.cylinders]) * 255
    assert np.allclose(rgb[:2], CHANGED) and np.allclose(rgb[2:], ROBOT)  # the filter changed robots 0 and 1
    border = ents["arena"].lines[0]
    assert [(p.x, p.y) for p in border.points] == [(-1.6, -1.0), (1.6, -1.0), (1.6, 1.0), (-1.6, 1.0)]
    poses, _ = _decoded(by_topic, TOPIC_POSES, len(frames) - 1)
    assert np.allclose([[p.position.x, p.position.y] for p in poses.poses], f.poses[:, :2])


def test_cells_barrier_and_contacts_are_line_and_marker_primitives(session):
    _, frames, by_topic = session
    f = frames[-1]
    cells, _ = _decoded(by_topic, TOPIC_CELLS, len(frames) - 1)
    line = cells.entities[0].lines[0]
    assert line.type == fm.LinePrimitiveLineType.LineList.value
    assert np.allclose([[p.x, p.y] for p in line.points], f.coverage.edges.reshape(-1, 2))
    bar, _ = _decoded(by_topic, TOPIC_BARRIER, len(frames) - 1)
    pts = np.array([[p.x, p.y] for p in bar.entities[0].lines[0].points])
    lp = f.points
    assert np.allclose(pts, [lp[0], lp[1], lp[2], lp[5]])
    cols = bar.entities[0].lines[0].colors
    assert len(cols) == 4 and cols[0].g < cols[2].g  # h ≤ 0 is red, h > 0 towards yellow
    for i, fr in enumerate(frames):  # no active pairs: the entity is replaced by an empty one
        lines = _decoded(by_topic, TOPIC_BARRIER, i)[0].entities[0].lines
        assert sum(len(ln.points) for ln in lines) == 2 * len(fr.barrier.active_pairs)
    con, _ = _decoded(by_topic, TOPIC_CONTACTS, len(frames) - 1)
    assert [(s.pose.position.x, s.pose.position.y) for s in con.entities[0].spheres] == [(0.2, -0.1)]


def test_density_grid_holds_phi_at_cell_centres(session):
    _, frames, by_topic = session
    grid, msg = _decoded(by_topic, TOPIC_DENSITY, 0)
    w = grid.column_count
    h = len(grid.data) // grid.row_stride
    assert (w, h) == (32, 20) and grid.cell_stride == 4 and grid.fields[0].name == "phi"  # 0.1 m cells
    phi = np.frombuffer(grid.data, dtype="<f4").reshape(h, w)
    x = -1.6 + (np.arange(w) + 0.5) * grid.cell_size.x
    y = -1.0 + (np.arange(h) + 0.5) * grid.cell_size.y
    gx, gy = np.meshgrid(x, y)
    expect = frames[0].density.evaluate(np.stack((gx, gy), axis=-1))
    assert np.allclose(phi, expect, rtol=1e-6)
    assert (grid.pose.position.x, grid.pose.position.y) == (-1.6, -1.0)
    # one grid per density_period (0.25 s) of recorded time, not one per frame
    assert 1 <= len(by_topic[TOPIC_DENSITY]) < len(frames)


def test_camera_transforms_log_and_metrics(session):
    _, frames, by_topic = session
    img, _ = _decoded(by_topic, TOPIC_CAMERA, 0)
    assert img.format == "jpeg" and img.frame_id == "camera"
    pic = cv2.imdecode(np.frombuffer(img.data, np.uint8), cv2.IMREAD_COLOR)
    assert pic.shape == (60, 96, 3)
    tf, _ = _decoded(by_topic, TOPIC_TF, 0)
    assert [(t.parent_frame_id, t.child_frame_id) for t in tf.transforms] == [("world", "arena"), ("arena", "camera")]
    logs = [_decoded(by_topic, TOPIC_LOG, i)[0] for i in range(len(by_topic[TOPIC_LOG]))]
    texts = [(lg.level, lg.message) for lg in logs]
    assert (fm.LogLevel.Info.value, "event 0") in texts and (fm.LogLevel.Info.value, "event 3") in texts
    assert (fm.LogLevel.Warning.value, "script failing") in texts
    assert (fm.LogLevel.Info.value, "cleared: script failing") in texts
    assert any(lg.message == "e-stop" and lg.name == "operator" for lg in logs)
    metrics = [json.loads(m.data) for _, m in by_topic[TOPIC_METRICS]]
    assert metrics[-1]["min_distance_m"] == 0.16 and metrics[-1]["robots_changed"] == 2
    assert metrics[-1]["cost_H"] == pytest.approx(frames[-1].coverage.cost_H)
    assert [m["tick"] for m in metrics] == [f.tick for f in frames]


def _topics_in_layout(obj, out):
    """Every topic name a Foxglove layout refers to (topic settings keys, topic fields, message paths)."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            if k == "topics" and isinstance(v, dict):
                out.update(v)
            elif k in ("topicToRender", "imageTopic") and v:
                out.add(v)
            elif k == "value" and isinstance(v, str) and v.startswith("/"):
                out.add(v.split(".")[0])
            _topics_in_layout(v, out)
    elif isinstance(obj, list):
        for v in obj:
            _topics_in_layout(v, out)
    return out


def test_the_shipped_layout_refers_only_to_recorded_topics(session, tmp_path, capsys):
    path, _, by_topic = session
    assert cli(["foxglove-layout", "-o", str(tmp_path / "layout.json")]) == 0
    layout = json.loads((tmp_path / "layout.json").read_text())
    assert layout == json.loads(files("swarmdeck.console.recording").joinpath("foxglove_layout.json").read_text())
    used = _topics_in_layout(layout, set())
    assert {TOPIC_ROBOTS, TOPIC_CELLS, TOPIC_BARRIER, TOPIC_DENSITY, TOPIC_LOG, TOPIC_CAMERA, TOPIC_METRICS} <= used
    recorded = set(by_topic) | set(PACKED_TOPICS)  # the per-entity session's topics and the packed form's
    assert used <= recorded, f"layout refers to topics no recording has: {used - recorded}"
    plotted = {v["value"].split(".", 1)[1] for p in layout["configById"].values() for v in p.get("paths", [])}
    assert plotted <= set(METRICS_SCHEMA["properties"])
    panels = set(layout["configById"])

    def leaves(node):
        return [node] if isinstance(node, str) else leaves(node["first"]) + leaves(node["second"])
    assert sorted(leaves(layout["layout"])) == sorted(panels)
    with open(path, "rb") as fh:
        declared = {ch.topic for ch in make_reader(fh).get_summary().channels.values()}
    assert set(CHANNELS) | set(TOPICS) <= declared  # swarmdeck's own channels are still there
    with open_recording(path) as r:
        assert r.count_frames() == len(by_topic[TOPIC_FRAME])


def test_a_failing_camera_never_costs_a_frame(tmp_path):
    loop = ControlLoop(LoopConfig(n_robots=4, seed=2))
    frames = [dataclasses.replace(loop.tick(), image_ref="camera:1") for _ in range(3)]

    def broken(ref):
        raise RuntimeError("camera unplugged")

    with Recorder(tmp_path / "x.mcap", image_provider=broken) as rec:
        for f in frames:
            rec.write_frame(f)
    st = rec.status()
    assert st.frames == 3 and "Foxglove channels failed: RuntimeError: camera unplugged" in st.message
    with open_recording(tmp_path / "x.mcap") as r:
        assert [f.tick for _, f in r.frames()] == [f.tick for f in frames]
