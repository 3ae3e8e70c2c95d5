"""Benchmark of line-segment obstacles (issue 28 item 3): what segments cost per tick.

Run: ``.venv/bin/python bench/bench_obstacles.py [--sizes 100,1000] [--ticks 20]`` (BLAS pinned to one thread).

Scene: N robots on a grid (``safety.scenes.grid_scene``, the arena scaled with N as in ``bench_safety.py``) with
square boxes of 0.3 m (4 segments each) on a 0.9 m lattice over the floor, robots closer than 0.115 m to a box
removed (so N is a little under the nominal size), random nominal directions at up to v_max. Per size, in thread CPU
ms (robust to other load), median over ``ticks`` closed-loop ticks x ← x + u·dt:

* *segment rows*: ``safety.constraints.segment_rows`` alone (the k-d tree query and the rows);
* *filter, no obstacles* / *filter, obstacles*: one ``devices.pipeline.barrier_filter`` call (the pipeline's
  defaults: mode auto, bounded work) on the same poses, without and with the segments;
* *simulator step, obstacles*: ``SimulatedArena.step`` with the segments (contact test), and without.
"""
from __future__ import annotations

import argparse

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np  # noqa: E402

from swarmdeck.core.bounds import Bounds  # noqa: E402
from swarmdeck.core.kinematics import GritsBotParams, lookahead_points  # noqa: E402
from swarmdeck.core.obstacles import START_CLEARANCE, Obstacles, point_segment_distance  # noqa: E402
from swarmdeck.devices.pipeline import barrier_filter  # noqa: E402
from swarmdeck.devices.simulator import ArenaConfig, SimulatedArena  # noqa: E402
from swarmdeck.safety import BarrierConfig  # noqa: E402
from swarmdeck.safety.constraints import segment_rows  # noqa: E402
from swarmdeck.safety.scenes import arena_for, grid_scene  # noqa: E402

PITCH = 0.26


def boxes(bounds: Bounds, spacing: float = 0.9, side: float = 0.3) -> Obstacles:
    """Square boxes of ``side`` m on a ``spacing`` m lattice inside ``bounds``."""
    b = Bounds.of(bounds)
    xs = np.arange(b.x_min + spacing / 2, b.x_max - spacing / 4, spacing)
    ys = np.arange(b.y_min + spacing / 2, b.y_max - spacing / 4, spacing)
    h = side / 2
    square = np.array([[-h, -h], [h, -h], [h, h], [-h, h]])
    return Obstacles.from_polygons([square + [x, y] for x in xs for y in ys])


def scene(n: int, seed: int) -> tuple[BarrierConfig, Obstacles, np.ndarray]:
    cfg = BarrierConfig(bounds=arena_for(n, PITCH, fill=0.8))
    rng = np.random.default_rng(seed)
    pts, _ = grid_scene(n, rng, cfg, pitch=PITCH)
    obs = boxes(cfg.bounds)
    keep = point_segment_distance(pts, obs.segments).min(axis=1) >= START_CLEARANCE
    pts = pts[keep]
    poses = np.column_stack([pts, rng.uniform(-np.pi, np.pi, len(pts))])
    return cfg, obs, poses


def run(n: int, ticks: int, seed: int) -> dict[str, float]:
    cfg, obs, poses = scene(n, seed)
    robot = GritsBotParams()
    rng = np.random.default_rng(seed + 1)
    v = rng.uniform(0.0, robot.max_speed, len(poses))
    w = rng.uniform(-1.0, 1.0, len(poses))
    plain = barrier_filter(robot, cfg.bounds, cfg.dt)
    walls = barrier_filter(robot, cfg.bounds, cfg.dt, obstacles=obs)
    sim_plain = SimulatedArena(initial_poses=poses, config=ArenaConfig(bounds=cfg.bounds))
    sim_obs = SimulatedArena(initial_poses=poses, config=ArenaConfig(bounds=cfg.bounds, obstacles=obs))
    seg_cfg = walls.config
    out: dict[str, list[float]] = {k: [] for k in ("rows", "plain", "obstacles", "sim_plain", "sim_obs")}
    for _ in range(ticks):
        x = sim_obs.poses
        pts = lookahead_points(x, robot.lookahead)
        t, _ = harness.timed(segment_rows, pts, seg_cfg, clock="thread")
        out["rows"].append(t)
        t, _ = harness.timed(plain.filter, x, v, w, clock="thread")
        out["plain"].append(t)
        t, (vs, ws, diag) = harness.timed(walls.filter, x, v, w, clock="thread")
        out["obstacles"].append(t)
        assert diag.ok, diag.status
        t, _ = harness.timed(sim_plain.step, vs, ws, clock="thread")
        out["sim_plain"].append(t)
        t, _ = harness.timed(sim_obs.step, vs, ws, clock="thread")
        out["sim_obs"].append(t)
    assert sim_obs.report.steps_with_obstacle_contact == 0
    return {"n": float(len(poses)), "segments": float(obs.m),
            **{k: 1e3 * float(np.median(s)) for k, s in out.items()}}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="100,1000")
    ap.add_argument("--ticks", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    print(harness.machine())
    base = harness.baseline()
    print(f"baseline (sort 10^5 floats x10): {base.median_ms:.2f} ms")
    print("| N | segments | segment rows ms | filter ms, no obstacles | filter ms, obstacles | sim step ms, none | "
          "sim step ms, obstacles |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for n in (int(s) for s in args.sizes.split(",")):
        r = run(n, args.ticks, args.seed)
        print(f"| {int(r['n'])} | {int(r['segments'])} | {r['rows']:.2f} | {r['plain']:.2f} | {r['obstacles']:.2f} | "
              f"{r['sim_plain']:.3f} | {r['sim_obs']:.3f} |")


if __name__ == "__main__":
    main()
