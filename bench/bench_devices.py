"""Cost of one simulated arena step (physics + wheel limits + validation) for N = 10, 100, 1000.

Run: python bench/bench_devices.py   (prints a markdown table)

Baseline in the same process: the same step written the way rps does it, a
Python loop over robots for the dynamics and all-pairs collision checks.
"""
from __future__ import annotations

import platform
import time

import numpy as np

from swarmdeck.devices import ArenaConfig, SimulatedArena, random_initial_poses


def median_time(fn, repeats: int) -> float:
    samples = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - t0)
    return float(np.median(samples))


def looped_step(poses: np.ndarray, v: np.ndarray, w: np.ndarray, dt: float) -> np.ndarray:
    """rps-style reference: per-robot Euler step and an all-pairs collision test."""
    out = poses.copy()
    n = len(poses)
    for i in range(n):
        out[i, 0] += dt * v[i] * np.cos(out[i, 2])
        out[i, 1] += dt * v[i] * np.sin(out[i, 2])
        out[i, 2] += dt * w[i]
    shifted = out[:, :2] + 0.025 * np.column_stack((np.cos(out[:, 2]), np.sin(out[:, 2])))
    hits = 0
    for i in range(n):
        d = np.linalg.norm(shifted[i + 1:] - shifted[i], axis=1)
        hits += int(np.sum(d <= 0.135))
    return out


def main() -> None:
    rows = []
    for n in (10, 100, 1000):
        bounds = (-1.6, 1.6, -1.0, 1.0) if n <= 100 else (-8.0, 8.0, -5.0, 5.0)
        cfg = ArenaConfig(bounds=bounds, seed=0)
        sim = SimulatedArena(initial_poses=random_initial_poses(n, bounds, rng=0), config=cfg)
        rng = np.random.default_rng(1)
        v = rng.uniform(-0.2, 0.2, n)
        w = rng.uniform(-2, 2, n)
        repeats = 2000 if n <= 100 else 500
        t_ours = median_time(lambda: sim.step(v, w), repeats)  # noqa: B023  (timed at once)
        p = sim.poses
        t_loop = median_time(lambda: looped_step(p, v, w, cfg.dt), max(20, repeats // 10))  # noqa: B023  (timed at once)
        rows.append((n, t_ours * 1e3, t_loop * 1e3, t_loop / t_ours))
    print(f"machine: {platform.processor() or platform.machine()}, python {platform.python_version()}, numpy {np.__version__}")
    print("| N | swarmdeck step (ms, median) | per-robot loop baseline (ms) | speed-up |")
    print("| ---: | ---: | ---: | ---: |")
    for n, a, b, r in rows:
        print(f"| {n} | {a:.3f} | {b:.3f} | {r:.0f}x |")


if __name__ == "__main__":
    main()
