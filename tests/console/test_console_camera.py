"""--camera synthetic: the loop's poses come from the rendered overhead camera and ArUco tracking."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.console.runtime.hardware import camera_source
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.devices import ArenaConfig
from swarmdeck.devices.simulated_robots import SimulatedRobots


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


def test_camera_image_is_drawn_under_the_robots() -> None:
    import viser

    from swarmdeck.console.web.scene import ArenaScene

    cfg = LoopConfig(seed=2, n_robots=4)
    sim = SimulatedRobots(4, ArenaConfig(seed=2))
    src = camera_source("synthetic", np.arange(4), lambda now: sim.sim.poses, cfg.bounds)
    loop = ControlLoop(cfg, source=src, sink=sim)
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        scene = ArenaScene(server, cfg.bounds, image_provider=src.image)
        f = loop.tick()
        assert f.image_ref == "camera:0"
        scene.draw(f)
        img, bounds = src.image(f.image_ref)
        assert scene.nodes.camera is not None and img.shape[2] == 3 and bounds == cfg.bounds
    finally:
        server.stop()
