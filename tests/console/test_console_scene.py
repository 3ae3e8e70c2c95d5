"""The viser scene is a function of Frames: handles hold what the Frame says (live or recorded)."""
from __future__ import annotations

import json

import numpy as np
import pytest
import viser

from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.loop import ControlLoop, DensityParams, LoopConfig
from swarmdeck.console.web.app import FrameViewer
from swarmdeck.console.web.scene import ArenaScene, heatmap, robot_colors
from swarmdeck.coverage import GaussianMixture


@pytest.fixture(scope="module")
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


@pytest.fixture
def scene(server):
    server.scene.reset()
    return ArenaScene(server)


def _frames(n_robots: int = 6, ticks: int = 5, **kw) -> list[Frame]:
    loop = ControlLoop(LoopConfig(seed=4, n_robots=n_robots, **kw))
    return [loop.tick() for _ in range(ticks)]


def test_handles_follow_the_frame(scene) -> None:
    frames = _frames()
    for f in frames:
        scene.draw(f)
    f = frames[-1]
    np.testing.assert_allclose(scene.nodes.robots.batched_positions[:, :2], f.poses[:, :2], atol=1e-6)
    yaw = 2 * np.arctan2(scene.nodes.robots.batched_wxyzs[:, 3], scene.nodes.robots.batched_wxyzs[:, 0])
    np.testing.assert_allclose(np.angle(np.exp(1j * (yaw - f.poses[:, 2]))), 0.0, atol=1e-5)
    assert scene.nodes.voronoi.points.shape == (len(f.coverage.edges), 2, 3)
    np.testing.assert_allclose(scene.nodes.voronoi.points[:, :, :2], f.coverage.edges, atol=1e-6)
    np.testing.assert_allclose(scene.nodes.centroids.points[:, :2], f.coverage.centroids, atol=1e-6)
    np.testing.assert_allclose(scene.nodes.safe.points[:, 0, :2], f.points, atol=1e-6)
    assert scene.nodes.discs.points.shape == (f.n * scene.style.disc_segments, 2, 3)
    assert [lab.text for lab in scene.nodes.labels] == [str(i) for i in f.ids]


def test_recorded_frames_draw_the_same(scene) -> None:
    f = _frames(ticks=3)[-1]
    g = Frame.from_dict(json.loads(json.dumps(f.to_dict())))
    scene.draw(g)
    np.testing.assert_allclose(scene.nodes.robots.batched_positions[:, :2], f.poses[:, :2], atol=1e-6)


def test_robot_count_change_rebuilds_robots(scene) -> None:
    scene.draw(_frames(n_robots=4, ticks=1)[0])
    assert len(scene.nodes.labels) == 4
    scene.draw(_frames(n_robots=9, ticks=1)[0])
    assert len(scene.nodes.labels) == 9 and scene.nodes.robots.batched_positions.shape == (9, 3)


def test_barrier_pairs_and_colours(scene) -> None:
    loop = ControlLoop(LoopConfig(seed=1, n_robots=8, behaviour="rendezvous"))
    f = next(fr for fr in (loop.tick() for _ in range(400)) if fr.barrier.n_active > 0 and len(fr.barrier.active_pairs))
    scene.draw(f)
    pairs = f.barrier.active_pairs
    np.testing.assert_allclose(scene.nodes.barrier.points[:, 0, :2], f.points[pairs[:, 0]], atol=1e-6)
    cols = robot_colors(f)
    changed = f.barrier.intervention > 1e-3
    assert changed.any() and np.all(cols[changed] == (255, 140, 0))


def test_heatmap_is_upright() -> None:
    g = GaussianMixture(0.01, mu=[[1.0, 0.5]], sigma=[0.2], weight=[1.0])
    img = heatmap(g, (-1.6, 1.6, -1.0, 1.0), 50.0)
    assert img.shape == (100, 160, 3)
    r, c = np.unravel_index(np.argmin(img[:, :, 1].astype(int)), img.shape[:2])  # the peak is the least green
    assert r == pytest.approx(25, abs=2) and c == pytest.approx(130, abs=2)  # row 0 is y_max


def test_trails_reset_on_a_jump(scene) -> None:
    frames = _frames(ticks=10)
    for f in frames:
        scene.draw(f)
    assert not np.allclose(scene._trail[0], scene._trail[-1])
    scene.draw(frames[2])  # a seek backwards
    np.testing.assert_allclose(scene._trail[0], frames[2].poses[:, :2])


def test_viewer_keeps_only_the_newest_frame(scene) -> None:
    viewer = FrameViewer(scene)
    frames = _frames(ticks=4, density=DensityParams(moving=False))
    for f in frames:
        viewer.offer(f)
    assert viewer.draw_pending() is frames[-1]
    assert viewer.skipped == 3 and viewer.draw_pending() is None
