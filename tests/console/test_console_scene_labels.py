"""Robot id labels move with their robots every drawn frame (they trailed moving robots)."""
from __future__ import annotations

import numpy as np
import viser

from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.web.scene import ArenaScene


def test_labels_sit_on_their_robots_after_every_draw() -> None:
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        scene = ArenaScene(server)
        loop = ControlLoop(LoopConfig(seed=5, n_robots=6, behaviour="goto", max_speed=0.2))
        moved = 0.0
        prev = None
        for _ in range(12):
            f = loop.tick()
            scene.draw(f)
            label_xy = np.array([lab.position[:2] for lab in scene.nodes.labels], dtype=float)
            expected = f.poses[:, :2] + [0.0, scene.style.label_offset]
            np.testing.assert_allclose(label_xy, expected, atol=1e-6)
            robots_xy = scene.nodes.robots.batched_positions[:, :2]
            np.testing.assert_allclose(label_xy - [0.0, scene.style.label_offset], robots_xy, atol=1e-6)
            if prev is not None:
                moved = max(moved, float(np.abs(f.poses[:, :2] - prev).max()))
            prev = f.poses[:, :2].copy()
        assert 0.0 < moved < 0.01  # small per-tick moves: exactly what a "moved enough" threshold skipped
    finally:
        server.stop()
