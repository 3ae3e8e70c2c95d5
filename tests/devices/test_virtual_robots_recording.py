"""Virtual robots are marked in every Frame, in recordings (both frame formats) and in the scene; recordings
made before the mark existed still read, as all physical."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import viser

from swarmdeck.console.recording.codec import decode_frame, encode_frame
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.web.scene import ROBOT, ArenaScene, robot_colors
from swarmdeck.devices import ArenaConfig
from swarmdeck.devices.simulated_robots import SimulatedRobots
from swarmdeck.devices.virtual_robots import MixedRobots

FORMAT1 = Path(__file__).resolve().parents[1] / "data" / "recording_format1.mcap"


@pytest.fixture(scope="module")
def frames() -> list[Frame]:
    physical = SimulatedRobots(3, ArenaConfig(seed=8))
    mixed = MixedRobots.add_virtual(physical, physical, 2, ArenaConfig(seed=9))
    loop = ControlLoop(LoopConfig(n_robots=3), source=mixed, sink=mixed)
    try:
        return [loop.tick() for _ in range(5)]
    finally:
        loop.close()


def test_recordings_mark_the_virtual_robots(tmp_path, frames):
    assert frames[-1].is_virtual.tolist() == [False, False, False, True, True]
    path = tmp_path / "mixed.mcap"
    with Recorder(path) as rec:
        for f in frames:
            rec.write_frame(f)
    with open_recording(path) as r:
        got = [f for _, f in r.frames()]
    assert [g.is_virtual.tolist() for g in got] == [f.is_virtual.tolist() for f in frames]
    one = Frame.from_dict(json.loads(json.dumps(frames[-1].to_dict())))  # frame format 1
    assert one.is_virtual.tolist() == frames[-1].is_virtual.tolist()


def test_old_recordings_and_frames_without_the_mark_read_as_all_physical(frames):
    with open_recording(FORMAT1) as r:
        old = [f for _, f in r.frames()]
    assert old and all(not f.is_virtual.any() and f.is_virtual.shape == (f.n,) for f in old)
    d = frames[-1].to_dict()
    del d["is_virtual"]
    assert not Frame.from_dict(d).is_virtual.any()
    plain = ControlLoop(LoopConfig(n_robots=3, seed=1)).tick()
    assert "is_virtual" not in plain.to_dict() and b"is_virtual" not in encode_frame(plain)  # unchanged when unused
    bad = json.loads(encode_frame(frames[-1]))
    bad["is_virtual"]["shape"] = [2]
    bad["is_virtual"]["b64"] = "AAE="
    with pytest.raises(ValueError, match="is_virtual"):
        decode_frame(json.dumps(bad).encode())


def test_scene_draws_virtual_robots_pale_and_ringed(frames):
    f = frames[-1]
    cols = robot_colors(f)
    assert (cols[:3] == ROBOT).all()
    assert (cols[3:] > ROBOT).all()  # blended toward white
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        scene = ArenaScene(server)
        scene.draw(f)
        rings = scene.nodes.virtual.points
        assert rings.shape == (2 * 8, 2, 3)  # 8 dashes per virtual robot
        centres = rings[:, 0, :2].reshape(2, 8, 2).mean(axis=1)
        np.testing.assert_allclose(centres, f.poses[3:, :2], atol=1e-3)
        scene.draw(Frame(**{k: getattr(f, k) for k in ("tick", "time", "poses", "ids", "nominal", "safe", "v", "w")}))
        assert scene.nodes.virtual.points[:, :, 2].max() < 0  # no virtual robots: the hidden stub
    finally:
        server.stop()
