"""The robots' sensor readings in the Frame and the recording (issue 28.1): written only when present, round trips
through JSON (exact) and the compact codec (float32), bad shapes named, and `swarmdeck run --record` (ArenaRecording)
writes what an Arena with sensors sensed at each frame's poses, so `swarmdeck play` and Foxglove see it."""
from __future__ import annotations

import json

import numpy as np
import pytest

from swarmdeck.console.recording.arena_recording import ArenaRecording
from swarmdeck.console.recording.codec import decode_frame, encode_frame
from swarmdeck.console.recording.reader import Recording
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.sensors_frame import SensorsFrame
from swarmdeck.devices import Arena
from swarmdeck.devices.arena import RUN_DEFAULTS, RunDefaults
from swarmdeck.devices.simulator import ArenaConfig
from swarmdeck.sensing import DistanceSensorConfig, SensingConfig


def _arena() -> Arena:
    ic = np.array([[-0.5, 0.0, 0.0], [-0.1, 0.0, np.pi], [0.6, 0.4, 1.0]])
    return Arena(initial_conditions=ic, config=ArenaConfig(seed=3), safety=False,
                 sensing=SensingConfig(distance=DistanceSensorConfig()))


def _frame(arena: Arena, sensors: SensorsFrame | None) -> Frame:
    n = arena.n
    return Frame(tick=0, time=0.0, poses=arena.poses(), ids=np.arange(n), nominal=np.zeros((n, 2)),
                 safe=np.zeros((n, 2)), v=np.zeros(n), w=np.zeros(n), sensors=sensors)


def test_sensors_round_trip_through_json_and_the_codec():
    arena = _arena()
    arena.set_leds(np.array([[255, 0, 0], [0, 255, 0], [0, 0, 0]]))
    arena.step()
    sf = SensorsFrame.of(arena.sense(), arena.sensors.config)
    f = _frame(arena, sf)
    g = Frame.from_dict(json.loads(json.dumps(f.to_dict())))
    for name in ("distances", "leds", "encoders", "imu"):
        assert np.array_equal(getattr(g.sensors, name), getattr(f.sensors, name), equal_nan=True), name
    h = decode_frame(encode_frame(f))
    np.testing.assert_allclose(h.sensors.distances, f.sensors.distances, rtol=1e-6)
    assert h.sensors.leds.tolist() == [[255, 0, 0], [0, 255, 0], [0, 0, 0]]
    assert np.array_equal(h.sensors.encoders, f.sensors.encoders)
    np.testing.assert_allclose(h.sensors.imu, f.sensors.imu, rtol=1e-6)


def test_frames_without_sensors_write_no_sensors_key():
    arena = Arena(2, config=ArenaConfig(seed=1))
    f = _frame(arena, None)
    assert "sensors" not in f.to_dict()
    assert "sensors" not in json.loads(encode_frame(f))
    assert decode_frame(encode_frame(f)).sensors is None


def test_bad_sensor_shapes_are_named():
    arena = _arena()
    good = SensorsFrame.of(arena.sense(), arena.sensors.config)
    with pytest.raises(ValueError, match="'sensors' has 3 rows but there are 2 poses"):
        Frame(tick=0, time=0.0, poses=np.zeros((2, 3)), ids=np.arange(2), nominal=np.zeros((2, 2)),
              safe=np.zeros((2, 2)), v=np.zeros(2), w=np.zeros(2), sensors=good)
    with pytest.raises(ValueError, match=r"'sensors.leds' must have shape \(n,3\)"):
        SensorsFrame(sensor_poses=np.zeros((7, 3)), leds=np.zeros((3, 4)))
    d = _frame(arena, good).to_dict()
    d["sensors"]["distances"] = [[0.1, 0.2]] * 3
    with pytest.raises(ValueError, match="sensors.distances"):
        Frame.from_dict(d)


def test_a_recorded_run_carries_what_the_robots_sensed_at_each_frames_poses(tmp_path):
    path = tmp_path / "run.mcap"
    rec = ArenaRecording(path, script="s.py", seed=3)
    token = RUN_DEFAULTS.set(RunDefaults(on_create=rec.on_create, on_step=rec.on_step))
    try:
        arena = _arena()
        sensed = [arena.sense().distances.copy()]
        for _ in range(5):
            arena.set_unicycle(np.array([0.05, 0.0, 0.1]), np.array([0.0, 0.5, 0.0]))
            arena.step()
            sensed.append(arena.sense().distances.copy())
    finally:
        RUN_DEFAULTS.reset(token)
    rec.close()
    frames = [f for _, f in Recording(path).frames()]
    assert len(frames) == 5
    assert np.isnan(frames[0].sensors.distances).all()  # the poses before the first step: nothing read yet
    for k, f in enumerate(frames[1:], start=1):
        np.testing.assert_allclose(f.sensors.distances, sensed[k], rtol=1e-6)
        rays = f.sensors.rays(f.poses)
        assert rays is not None and rays[0].shape == (3, 7, 2)
    # robots 0 and 1 face each other 0.4 m apart: robot 0's front sensor reads the gap (or a dropout/outlier)
    assert frames[1].sensors.distances[0, 3] != 0
