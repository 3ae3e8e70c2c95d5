"""The console at N = 1000: no robot cap, any arena size, a safe covering swarm, a scene that scales.

On a virtual clock (``loop.tick()``): 1000 robots in a 10 × 6 m arena get a layout, coverage
commands and the distributed barrier ("auto" above 200 robots); no two look-ahead points come
closer than D_s and every tick's frame is complete. The scene draws them as one batched mesh and
one Voronoi node, without labels or per-robot glyphs; a 12-robot scene keeps them.
"""
from __future__ import annotations

import numpy as np
import pytest
import viser
from scipy.spatial import cKDTree

from swarmdeck.console.cli import main
from swarmdeck.console.runtime.config import ConfigFileError, arena_bounds, load_settings
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig, SafetyParams
from swarmdeck.console.web.scene import ArenaScene

ARENA = arena_bounds("10x6")


@pytest.fixture(scope="module")
def run():
    loop = ControlLoop(LoopConfig(n_robots=1000, seed=2, bounds=ARENA))
    frames = [loop.tick() for _ in range(40)]
    loop.close()
    return frames


def test_a_thousand_robots_cover_safely(run) -> None:
    for f in run:
        assert f.n == 1000 and f.barrier.ok, f.barrier.status
        assert f.coverage is not None and len(f.coverage.edges) > 2000
        d = cKDTree(f.points).query(f.points, k=2)[0][:, 1].min()
        assert d >= f.barrier.safety_distance - 1e-6  # no collision (look-ahead points ≥ D_s apart)
        assert f.params["barrier_mode"] == "auto"
    assert run[-1].barrier.status.startswith("optimal per robot")  # distributed above 200 robots
    moved = np.linalg.norm(run[-1].poses[:, :2] - run[0].poses[:, :2], axis=1)
    assert np.mean(moved > 0.005) > 0.4  # they really move (40 ticks: 1.3 s)


def test_scene_scales(run) -> None:
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        big = ArenaScene(server, ARENA)
        for f in run[-3:]:  # the first draw builds the robots, later ones move them
            big.draw(f)
        assert big.nodes.labels == [] and not big.nodes.nominal.visible and not big.nodes.trails.visible
        assert big.nodes.robots.batched_positions.shape == (1000, 3)
        assert big.nodes.voronoi.points.shape == (len(run[-1].coverage.edges), 2, 3)
        img = big.nodes.density.image
        assert img.shape[0] * img.shape[1] <= big.style.heatmap_max_px
        server.scene.reset()
        loop = ControlLoop(LoopConfig(n_robots=12, seed=1))
        small = ArenaScene(server)
        small.draw(loop.tick())
        loop.close()
        assert len(small.nodes.labels) == 12 and small.nodes.nominal.visible
    finally:
        server.stop()


def test_arena_sizes_and_the_robot_limit(tmp_path, capsys) -> None:
    assert arena_bounds("10x6") == (-5.0, 5.0, -3.0, 3.0) and arena_bounds("3.2×2") == (-1.6, 1.6, -1.0, 1.0)
    for bad in ("10", "10x", "axb", "-1x2", "0x3"):
        with pytest.raises(ValueError, match="arena"):
            arena_bounds(bad)
    LoopConfig(n_robots=5000, bounds=ARENA)  # no cap in the config: what fits depends on the arena
    with pytest.raises(ValueError, match="mode"):
        SafetyParams(mode="onboard")
    cfg = tmp_path / "c.toml"
    cfg.write_text('[console]\narena = "10x6"\nrobots = 1000\n[safety]\nmode = "distributed"\n')
    s = load_settings(cfg)
    assert s.loop.bounds == ARENA and s.loop.n_robots == 1000 and s.loop.safety.mode == "distributed"
    cfg.write_text('[console]\narena = "10x6"\nbounds = [-1, 1, -1, 1]\n')
    with pytest.raises(ConfigFileError, match="arena or bounds"):
        load_settings(cfg)
    # too many for the arena: one line naming the maximum for that arena, exit 2
    assert main(["console", "--robots", "5000", "--arena", "10x6", "--no-record", "--no-inputs", "--port", "0",
                 "--duration", "0.1"]) == 2
    assert "at most 1148" in capsys.readouterr().err
    assert main(["console", "--arena", "ten-by-six", "--port", "0"]) == 2
    assert "--arena" in capsys.readouterr().err
