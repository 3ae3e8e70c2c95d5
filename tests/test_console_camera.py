"""--camera synthetic: the loop's poses come from the rendered overhead camera and ArUco tracking."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.console.hardware import camera_source
from swarmdeck.console.loop import ControlLoop, LoopConfig
from swarmdeck.console.robots import SimulatedRobots
from swarmdeck.devices import ArenaConfig


def test_tracked_poses_follow_the_simulation() -> None:
    cfg = LoopConfig(seed=2, n_robots=6, behaviour="goto")
    sim = SimulatedRobots(6, ArenaConfig(seed=2))
    loop = ControlLoop(cfg, source=camera_source("synthetic", np.arange(6), lambda now: sim.sim.poses, cfg.bounds),
                       sink=sim)
    for _ in range(4):
        truth = sim.sim.poses
        f = loop.tick()
        assert f.seen.all()
        assert np.max(np.hypot(*(f.poses[:, :2] - truth[:, :2]).T)) < 0.005
        assert np.max(np.abs(np.angle(np.exp(1j * (f.poses[:, 2] - truth[:, 2]))))) < 0.05
    assert "homography ok" in f.health["robots"]
    assert not f.stopped  # tracked robots are commanded


def test_bad_camera_spec_is_named() -> None:
    with pytest.raises(ValueError, match="not 'synthetic'"):
        camera_source("/no/such/video.mp4", np.arange(2), None, (-1.6, 1.6, -1.0, 1.0))
    with pytest.raises(ValueError, match="needs robots"):
        camera_source("synthetic", np.arange(2), None, (-1.6, 1.6, -1.0, 1.0))
