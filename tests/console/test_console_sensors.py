"""The robots' sensors in the console loop (issue 28.1): ``LoopConfig(sensors=True)`` (``[console] sensors = true``,
``swarmdeck console --sensors``) puts what the robots sensed at each tick's poses into every Frame — ToF readings,
encoders that count the motion, IMU, LEDs — seeded by the loop's seed; off by default; a failing sensor stage is
counted and alerted, never stops the robots."""
from __future__ import annotations

import numpy as np

from swarmdeck.console.runtime.config import load_settings
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig


def _frames(ticks: int = 12, **kw):
    loop = ControlLoop(LoopConfig(n_robots=6, seed=5, **kw))
    return loop, [loop.tick() for _ in range(ticks)]


def test_every_frame_carries_the_readings_at_its_poses():
    _, frames = _frames(sensors=True)
    for f in frames:
        s = f.sensors
        assert s is not None and s.distances.shape == (6, 7) and s.encoders.shape == (6, 2) and s.imu.shape == (6, 10)
        d = s.distances
        assert ((d == -1) | ((d >= 0) & (d <= 1.2))).all()
        assert s.rays(f.poses) is not None
    assert (frames[0].sensors.encoders == 0).all()
    moved = np.hypot(*(frames[-1].poses[:, :2] - frames[0].poses[:, :2]).T)
    counts = np.abs(frames[-1].sensors.encoders).sum(axis=1)
    assert (counts[moved > 0.01] > 0).all()  # robots that moved turned their wheels


def test_the_same_seed_gives_the_same_readings_and_sensors_are_off_by_default():
    _, a = _frames(sensors=True)
    _, b = _frames(sensors=True)
    for fa, fb in zip(a, b):
        assert np.array_equal(fa.sensors.distances, fb.sensors.distances)
    _, plain = _frames(ticks=2)
    assert all(f.sensors is None for f in plain)


def test_a_failing_sensor_stage_alerts_and_keeps_the_robots_going():
    loop, _ = _frames(ticks=1, sensors=True)

    def broken(*_a, **_k):
        raise RuntimeError("sensor bus down")

    loop._ticker.sensing.read = broken  # the stage's body fails from now on
    f = loop.tick()
    assert f.sensors is None
    assert any("sensors failed: RuntimeError: sensor bus down" in a for a in f.alerts)
    assert "robots stopped" not in " ".join(f.alerts)
    assert np.any(f.v != 0) or np.any(f.w != 0)


def test_the_config_file_key(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text("[console]\nrobots = 3\nsensors = true\n")
    assert load_settings(p).loop.sensors is True
