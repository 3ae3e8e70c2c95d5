"""Cost of one simulated arena step (physics + wheel limits + validation) for N = 10, 100, 1000.

Run: ``taskset -c 1 .venv/bin/python bench/bench_devices.py``   (prints a markdown table)

Baseline in the same process: the same step written the way rps does it, a
Python loop over robots for the dynamics and all-pairs collision checks.
Wall time (``perf_counter``), median and worst over the repeats.
"""
from __future__ import annotations

import harness  # first: pins BLAS before numpy loads
import numpy as np

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.constants import COLLISION_DISTANCE, COLLISION_SHIFT
from swarmdeck.devices import ArenaConfig, SimulatedArena, random_initial_poses


def looped_step(poses: np.ndarray, v: np.ndarray, w: np.ndarray, dt: float) -> np.ndarray:
    """rps-style reference: per-robot Euler step and an all-pairs collision test."""
    out = poses.copy()
    n = len(poses)
    for i in range(n):
        out[i, 0] += dt * v[i] * np.cos(out[i, 2])
        out[i, 1] += dt * v[i] * np.sin(out[i, 2])
        out[i, 2] += dt * w[i]
    shifted = out[:, :2] + COLLISION_SHIFT * np.column_stack((np.cos(out[:, 2]), np.sin(out[:, 2])))
    hits = 0
    for i in range(n):
        d = np.linalg.norm(shifted[i + 1:] - shifted[i], axis=1)
        hits += int(np.sum(d <= COLLISION_DISTANCE))
    return out


def main() -> None:
    rows = []
    for n in (10, 100, 1000):
        bounds = DEFAULT_BOUNDS if n <= 100 else Bounds(-8.0, 8.0, -5.0, 5.0)
        cfg = ArenaConfig(bounds=bounds, seed=0)
        sim = SimulatedArena(initial_poses=random_initial_poses(n, bounds, rng=0), config=cfg)
        rng = np.random.default_rng(1)
        v = rng.uniform(-0.2, 0.2, n)
        w = rng.uniform(-2, 2, n)
        repeats = 2000 if n <= 100 else 500
        ours = harness.measure(lambda: sim.step(v, w), repeats)  # noqa: B023 (called in this iteration)
        p = sim.poses
        loop = harness.measure(lambda: looped_step(p, v, w, cfg.dt), max(20, repeats // 10))  # noqa: B023
        rows.append((n, ours, loop))
    base = harness.baseline()
    print(harness.machine())
    print(f"same-process baseline (numpy sort 10⁵ ×10, thread CPU): {base.median_ms:.2f} ms")
    print(harness.table_header(["N", "swarmdeck step (ms, median (worst))", "per-robot loop baseline (ms, median)",
                                "speed-up"], [True] * 4))
    for n, ours, loop in rows:
        print(harness.table_row(n, ours, f"{loop.median_ms:.3f}", f"{loop.median / ours.median:.0f}x"))


if __name__ == "__main__":
    main()
