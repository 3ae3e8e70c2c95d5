"""The sensors' cost per step at rps 2.x sizes (issue 28: the rps 2.x examples' run time), one core.

Run: ``.venv/bin/python bench/bench_sensing_rps.py [--steps S] [--repeats R]``.

Per step, CPU time of this thread (``time.thread_time``) of

* **update**: ``Sensors.update`` as an Arena step calls it (rays cast once, one normal draw for the encoders and
  the IMU, fresh arrays frozen in place; numpy paths for a few robots: no numba, no scipy);
* **composed**: the same readings from one public model call per sensor (``true_distances``,
  ``noisy_distances``, ``sensor_rays``, ``distance_endpoints``, ``encoder_increment``, ``imu_readings``) and a
  frozen copy of each array — what ``Sensors.update`` did before (with today's models, so without the numba
  import the ray casts paid before: that one-off cost shows in ``bench/bench_rps2_examples.py``'s whole-process CPU).

The two run interleaved in one process (R rounds of S steps each, the order alternating), on the same poses and
commands, each with its own generator of the same seed; the readings are checked equal. Cells: median / worst of
the rounds' mean µs per step, and the load average beside them. Scenes: N robots in the rps arena, IMU and
encoders only (every rps example), and with the seven ToF sensors against the eight obstacle segments of rps 2.0's
``sensor_readings.py`` example.
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np  # noqa: E402

from swarmdeck.core.bounds import DEFAULT_BOUNDS  # noqa: E402
from swarmdeck.core.kinematics import GritsBotParams  # noqa: E402
from swarmdeck.sensing import (  # noqa: E402
    DistanceSensorConfig,
    SensingConfig,
    Sensors,
    distance_endpoints,
    encoder_increment,
    imu_readings,
    noisy_distances,
    sensor_rays,
    true_distances,
)

#: rps 2.0's sensor_readings.py obstacles (M, 2, 2) m
OBSTACLES = np.array([
    [[-1.0, -0.5], [-1.0, 0.5]], [[-0.6, -0.5], [-0.6, 0.5]], [[0.6, -0.5], [0.6, 0.5]], [[1.0, -0.5], [1.0, 0.5]],
    [[-1.4, -0.9], [-1.4, 0.9]], [[-1.4, 0.9], [1.4, 0.9]], [[1.4, 0.9], [1.4, -0.9]], [[1.4, -0.9], [-1.4, -0.9]],
])
DT = 0.033


class Composed:
    """One public model call per sensor, each array copied and frozen (``Sensors.update`` before)."""

    def __init__(self, n: int, config: SensingConfig, rng: np.random.Generator, obstacles: np.ndarray | None) -> None:
        self.n, self.config, self.rng, self.obstacles = n, config, rng, obstacles
        self.params = GritsBotParams()
        self.encoders = np.zeros((n, 2))
        self.v_prev, self.w_prev = np.zeros(n), np.zeros(n)

    def update(self, poses: np.ndarray, v: np.ndarray, w: np.ndarray, dt: float) -> list[np.ndarray]:
        cfg, out = self.config, []
        vv = np.nan_to_num(np.asarray(v, dtype=float).reshape(self.n), nan=0.0, posinf=0.0, neginf=0.0)
        ww = np.nan_to_num(np.asarray(w, dtype=float).reshape(self.n), nan=0.0, posinf=0.0, neginf=0.0)
        if cfg.distance is not None:
            true = true_distances(poses, cfg.distance, obstacles=self.obstacles, bounds=DEFAULT_BOUNDS)
            d = noisy_distances(true, cfg.distance, self.rng)
            out += [d, sensor_rays(poses, cfg.distance)[0], distance_endpoints(poses, d, cfg.distance)]
        assert cfg.imu is not None
        self.encoders = self.encoders + encoder_increment(vv, ww, dt, self.params, cfg.imu, self.rng)
        imu = imu_readings(vv, ww, self.v_prev, self.w_prev, poses[:, 2], dt, cfg.imu, self.rng)
        out += [self.encoders.astype(np.int64), imu.accel, imu.gyro, imu.mag, imu.orientation]
        self.v_prev, self.w_prev = vv, ww
        frozen = []
        for a in out:
            a = np.array(a, copy=True)
            a.flags.writeable = False
            frozen.append(a)
        return frozen


def _readings(r: object) -> list[np.ndarray]:
    names = ("distances", "origins", "endpoints", "encoders", "accel", "gyro", "mag", "orientation")
    return [getattr(r, k) for k in names if getattr(r, k) is not None]


def measure(n: int, tof: bool, steps: int, repeats: int) -> tuple[list[float], list[float]]:
    """Mean µs per step of each round: (update, composed)."""
    config = SensingConfig(distance=DistanceSensorConfig() if tof else None)
    obstacles = OBSTACLES if tof else None
    sensors = Sensors(n, config, rng=np.random.default_rng(1), obstacles=obstacles)
    composed = Composed(n, config, np.random.default_rng(1), obstacles)
    rng = np.random.default_rng(2)
    poses = np.column_stack((rng.uniform(-1.3, 1.3, (n, 2)), rng.uniform(-np.pi, np.pi, n)))
    v, w = rng.uniform(-0.1, 0.1, n), rng.uniform(-1.0, 1.0, n)
    for a, b in zip(_readings(sensors.update(poses, v, w, DT)), composed.update(poses, v, w, DT)):
        if not np.array_equal(a, b, equal_nan=True):
            raise SystemExit(f"N={n} tof={tof}: Sensors.update and the composed models disagree")
    ours: list[float] = []
    theirs: list[float] = []
    for r in range(repeats):
        order = ((sensors.update, ours), (composed.update, theirs))
        for fn, sink in order if r % 2 == 0 else order[::-1]:
            start = time.thread_time()
            for _ in range(steps):
                fn(poses, v, w, DT)
            sink.append((time.thread_time() - start) / steps * 1e6)
    return ours, theirs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=300, help="steps per round (an rps example: 304)")
    parser.add_argument("--repeats", type=int, default=7, help="rounds per scene")
    args = parser.parse_args()
    print(harness.machine())
    print("| N | sensors | Sensors.update µs/step median / worst | composed models µs/step median / worst | ratio | load |")
    print("| ---: | --- | ---: | ---: | ---: | ---: |")
    for n, tof in ((1, True), (3, False), (6, False), (12, False), (6, True), (12, True)):
        ours, theirs = measure(n, tof, args.steps, args.repeats)
        print(f"| {n} | {'IMU, encoders, ToF × 8 segments' if tof else 'IMU, encoders'} | "
              f"{statistics.median(ours):.0f} / {max(ours):.0f} | {statistics.median(theirs):.0f} / {max(theirs):.0f} | "
              f"{statistics.median(theirs) / statistics.median(ours):.2f} | {os.getloadavg()[0]:.1f} |", flush=True)
    loaded = sorted(m for m in ("numba", "scipy") if m in sys.modules)
    print(f"\nimported by the sensing steps above: {', '.join(loaded) if loaded else 'neither numba nor scipy'}")


if __name__ == "__main__":
    main()
