"""Foxglove channels at large N: the per-robot scene channels carry at most ``robot_rate`` robots per
second (every frame up to 100 robots at 30 Hz, every 10th frame at N = 1000), id labels only up to
``max_labels`` robots; the other channels keep their rates."""
from __future__ import annotations

import collections

import foxglove.messages as fm
import numpy as np
import pytest
from foxglove_schemas import decode

from swarmdeck.console.recording.foxglove import (
    TOPIC_BARRIER,
    TOPIC_CELLS,
    TOPIC_METRICS,
    TOPIC_POSES,
    TOPIC_ROBOTS,
    TOPIC_TF,
    FoxgloveConfig,
    FoxgloveEncoder,
)
from swarmdeck.console.runtime.frame import Frame

PER_ROBOT = (TOPIC_ROBOTS, TOPIC_POSES, TOPIC_CELLS, TOPIC_BARRIER)


def _frames(n: int, count: int, dt: float = 0.033, t0: float = 0.0) -> list[Frame]:
    rng = np.random.default_rng(n)
    out = []
    for k in range(count):
        poses = np.column_stack([rng.uniform(-4, 4, n), rng.uniform(-2.5, 2.5, n), rng.uniform(-3, 3, n)])
        z2 = np.zeros((n, 2))
        out.append(Frame(tick=k, time=t0 + k * dt, poses=poses, ids=np.arange(n), nominal=z2, safe=z2,
                         v=np.zeros(n), w=np.zeros(n), dt=dt, bounds=(-5.0, 5.0, -3.0, 3.0)))
    return out


def _written(enc: FoxgloveEncoder, frames: list[Frame]) -> dict[str, list[int]]:
    """topic -> indices of the frames that wrote it."""
    got = collections.defaultdict(list)
    for k, f in enumerate(frames):
        for topic, _, _ in enc.encode(f, 10**9 + k, f.time):
            got[topic].append(k)
    return got


@pytest.mark.parametrize("n,every", [(12, 1), (100, 1), (300, 3), (1000, 10)])
def test_per_robot_channels_carry_at_most_robot_rate_robots_per_second(n: int, every: int) -> None:
    frames = _frames(n, 30)
    got = _written(FoxgloveEncoder((-5.0, 5.0, -3.0, 3.0), config=FoxgloveConfig.per_entity()), frames)
    for topic in PER_ROBOT:
        assert got[topic] == list(range(0, 30, every)), topic
    for topic in (TOPIC_TF, TOPIC_METRICS):  # the cheap channels keep every frame
        assert got[topic] == list(range(30)), topic


def test_no_limit_writes_every_frame_and_a_smaller_rate_thins_more() -> None:
    frames = _frames(1000, 12)
    assert _written(FoxgloveEncoder(config=FoxgloveConfig(robot_rate=0)), frames)[TOPIC_ROBOTS] == list(range(12))
    assert _written(FoxgloveEncoder(config=FoxgloveConfig(robot_rate=1000)), frames)[TOPIC_ROBOTS] == [0]


def test_a_clock_that_jumps_back_gets_a_scene_at_once() -> None:
    enc = FoxgloveEncoder(config=FoxgloveConfig.per_entity())
    late = _frames(1000, 3, t0=100.0)
    early = _frames(1000, 1, t0=0.0)
    assert _written(enc, late)[TOPIC_ROBOTS] == [0]
    assert _written(enc, early)[TOPIC_ROBOTS] == [0]  # a new run's clock: not 100 s without robots


def _robots_entity(enc: FoxgloveEncoder, frame: Frame):
    schema = fm.SceneUpdate.get_schema()
    upd = decode(schema.name, bytes(schema.data), enc.robots(frame, 10**9))
    return {e.id: e for e in upd.entities}["robots"]


def test_labels_only_up_to_max_labels() -> None:
    enc = FoxgloveEncoder((-5.0, 5.0, -3.0, 3.0))
    small, big = _frames(100, 1)[0], _frames(101, 1)[0]
    assert [t.text for t in _robots_entity(enc, small).texts] == [str(i) for i in range(100)]
    robots = _robots_entity(enc, big)
    assert len(robots.cylinders) == len(robots.arrows) == 101 and len(robots.texts) == 0


@pytest.mark.parametrize("bad", [{"robot_rate": -1.0}, {"robot_rate": float("nan")}, {"max_labels": -1},
                                 {"max_labels": 2.5}, {"max_labels": True}])
def test_bad_thinning_settings_are_refused(bad) -> None:
    with pytest.raises(ValueError, match=next(iter(bad))):
        FoxgloveConfig(**bad)
