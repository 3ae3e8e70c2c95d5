"""Benchmark of the sensing layer (issue 28.1): its cost per tick at N = 20, 100, 1000 robots, one core.

Run: ``.venv/bin/python bench/bench_sensing.py [--ticks T] [N ...]``.

Scene: N robots on a jittered grid at pitch 0.25 m (``safety.scenes``; the default 3.2 × 2.0 m floor holds N = 20
and 100 there; N = 1000 gets an arena of the same aspect sized for it, ≈ 9.1 × 5.6 m), random headings, 12
random obstacle segments 0.2–0.8 m long, walls on; the robots move 1 cm per tick in a random walk between the
ticks. Per tick, CPU time of this thread (``time.thread_time``) of

* **tof**: the seven ToF sensors of every robot — ``true_distances`` (exact ray casts: bodies through the staged
  k-d tree, obstacles, walls) and ``noisy_distances`` (rps 2.0's dropout/outlier/error model);
* **imu**: encoders, accelerometer, gyro, magnetometer, orientation;
* **rb**: range and bearing to neighbours within 0.5 m;
* **update**: ``Sensors.update`` with all of them (what an Arena step pays), and its ratio to the 33 ms tick.

Medians and worst over the ticks (3 warm-up ticks left out).
"""
from __future__ import annotations

import argparse

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np  # noqa: E402

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds  # noqa: E402
from swarmdeck.core.constants import CONTROL_PERIOD  # noqa: E402
from swarmdeck.core.kinematics import GritsBotParams  # noqa: E402
from swarmdeck.safety import BarrierConfig  # noqa: E402
from swarmdeck.safety.scenes import arena_for, grid_scene  # noqa: E402
from swarmdeck.sensing import (  # noqa: E402
    DistanceSensorConfig,
    ImuConfig,
    RangeBearingConfig,
    SensingConfig,
    Sensors,
    encoder_increment,
    imu_readings,
    noisy_distances,
    range_and_bearing,
    true_distances,
)

PITCH = 0.25
N_OBSTACLES = 12


def scene(n: int, rng: np.random.Generator) -> tuple[np.ndarray, Bounds, np.ndarray]:
    bounds = DEFAULT_BOUNDS if n <= 100 else arena_for(n, PITCH)
    points, _ = grid_scene(n, rng, BarrierConfig(bounds=bounds), pitch=PITCH)
    poses = np.column_stack((points, rng.uniform(-np.pi, np.pi, n)))
    x0, x1, y0, y1 = bounds
    mid = np.column_stack((rng.uniform(x0, x1, N_OBSTACLES), rng.uniform(y0, y1, N_OBSTACLES)))
    ang = rng.uniform(0, np.pi, N_OBSTACLES)
    half = rng.uniform(0.1, 0.4, N_OBSTACLES)[:, None] * np.column_stack((np.cos(ang), np.sin(ang)))
    return poses, Bounds.of(bounds), np.stack((mid - half, mid + half), axis=1)


def tof_tick(poses: np.ndarray, tof: DistanceSensorConfig, obstacles: np.ndarray, bounds: Bounds,
             noise: np.random.Generator) -> np.ndarray:
    """The ToF readings of one tick: exact ray casts, then the reading model."""
    return noisy_distances(true_distances(poses, tof, obstacles=obstacles, bounds=bounds), tof, noise)


def imu_tick(v: np.ndarray, w: np.ndarray, poses: np.ndarray, params: GritsBotParams, imu: ImuConfig,
             noise: np.random.Generator) -> None:
    """Encoders and IMU of one tick."""
    encoder_increment(v, w, CONTROL_PERIOD, params, imu, noise)
    imu_readings(v, w, v, w, poses[:, 2], CONTROL_PERIOD, imu, noise)


def run(n: int, ticks: int) -> dict[str, harness.Timing]:
    rng = np.random.default_rng(n)
    poses, bounds, obstacles = scene(n, rng)
    tof = DistanceSensorConfig(walls=True)
    imu, rb = ImuConfig(), RangeBearingConfig()
    params = GritsBotParams()
    sensors = Sensors(n, SensingConfig(distance=tof, range_bearing=rb, imu=imu), rng=np.random.default_rng(1),
                      params=params, bounds=bounds, obstacles=obstacles)
    v, w = np.full(n, 0.1), rng.uniform(-1, 1, n)
    samples: dict[str, list[float]] = {"tof": [], "imu": [], "rb": [], "update": []}
    noise = np.random.default_rng(2)
    for tick in range(ticks + 3):
        poses = poses + np.column_stack((rng.normal(0, 0.01, (n, 2)), rng.normal(0, 0.05, n)))
        t_tof, _ = harness.timed(tof_tick, poses, tof, obstacles, bounds, noise, clock="thread")
        t_imu, _ = harness.timed(imu_tick, v, w, poses, params, imu, noise, clock="thread")
        t_rb, _ = harness.timed(range_and_bearing, poses, rb, noise, clock="thread")
        t_up, _ = harness.timed(sensors.update, poses, v, w, CONTROL_PERIOD, clock="thread")
        if tick >= 3:
            for key, t in (("tof", t_tof), ("imu", t_imu), ("rb", t_rb), ("update", t_up)):
                samples[key].append(t)
    return {k: harness.timing(s, "thread") for k, s in samples.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("n", nargs="*", type=int, default=[20, 100, 1000])
    ap.add_argument("--ticks", type=int, default=60)
    args = ap.parse_args()
    print(harness.machine())
    base = harness.baseline()
    print(f"baseline (harness sort, thread CPU) {base.ms()}")
    print(harness.table_header(["N", "tof ms (worst)", "imu ms (worst)", "rb ms (worst)", "update ms (worst)",
                                "update / 33 ms tick"], [True] * 6))
    for n in args.n:
        t = run(n, args.ticks)
        print(harness.table_row(n, t["tof"].ms(), t["imu"].ms(), t["rb"].ms(), t["update"].ms(),
                                f"{t['update'].median / CONTROL_PERIOD:.3f}"))


if __name__ == "__main__":
    main()
