"""The reading models' statistics over many seeded samples, within confidence bounds (REFERENCE.md §15): ToF
dropout and outlier rates, the mean and spread of kept readings; the IMU's noise; the same seed, the same readings.

Each count is checked against its binomial mean ± 5 standard deviations (one seed each: deterministic, and a
correct model fails such a bound with probability < 1e-6)."""
from __future__ import annotations

import math

import numpy as np

from swarmdeck.core.constants import ACCEL_NOISE, GRAVITY, GYRO_NOISE, MAG_XY, MAG_Z, TOF_DROPOUT, TOF_OUTLIER
from swarmdeck.sensing import DistanceSensorConfig, ImuConfig, imu_readings, noisy_distances

SAMPLES = 200_000


def within(count: int, n: int, p: float, z: float = 5.0) -> bool:
    return abs(count - n * p) <= z * math.sqrt(n * p * (1 - p))


def test_dropout_outlier_rates_and_the_kept_readings_mean_and_spread():
    cfg = DistanceSensorConfig()
    true = np.full((SAMPLES // 7, 7), 0.5)
    r = noisy_distances(true, cfg, np.random.default_rng(28))
    n = r.size
    dropped = int((r == -1.0).sum())
    assert within(dropped, n, TOF_DROPOUT)
    kept = r[r != -1.0]
    # a kept reading is an outlier (uniform on [0, 1.2]) with probability 1.4 %; the rest are N(0.5, (0.03·0.5)²)
    far = int((np.abs(kept - 0.5) > 0.2).sum())  # > 13 σ of the regular readings: outliers only
    p_far = TOF_OUTLIER * (1.2 - 0.4) / 1.2
    assert within(far, len(kept), p_far)
    regular = kept[np.abs(kept - 0.5) < 0.1]
    sigma = cfg.error * 0.5
    assert abs(regular.mean() - 0.5) <= 5 * sigma / math.sqrt(len(regular)) + 1e-4  # outliers inside ±0.1 shift it little
    assert abs(regular.std() / sigma - 1) < 0.05
    assert (r <= cfg.max_range).all() and ((r >= 0) | (r == -1)).all()


def test_nothing_in_range_always_reads_minus_one():
    cfg = DistanceSensorConfig()
    r = noisy_distances(np.full((1000, 7), np.inf), cfg, np.random.default_rng(1))
    assert (r == -1.0).all()
    r = noisy_distances(np.full((10, 7), cfg.max_range), cfg, np.random.default_rng(1))
    assert (r == -1.0).all()  # exactly at the range is out of it, as rps 2.0


def test_the_same_seed_gives_the_same_readings_and_another_seed_others():
    cfg = DistanceSensorConfig()
    true = np.random.default_rng(0).uniform(0, 1.5, (50, 7))
    a = noisy_distances(true, cfg, np.random.default_rng(5))
    b = noisy_distances(true, cfg, np.random.default_rng(5))
    c = noisy_distances(true, cfg, np.random.default_rng(6))
    assert np.array_equal(a, b) and not np.array_equal(a, c)


def test_imu_noise_matches_the_configured_sigmas_and_means():
    cfg = ImuConfig()
    n = 50_000
    v = np.full(n, 0.1)
    w = np.zeros(n)
    th = np.zeros(n)
    imu = imu_readings(v, w, v, w, th, 0.033, cfg, np.random.default_rng(3))
    assert np.allclose(imu.accel.std(axis=0), ACCEL_NOISE, rtol=0.03)
    assert np.allclose(imu.accel.mean(axis=0), [0.0, 0.0, -GRAVITY], atol=5 * np.array(ACCEL_NOISE) / math.sqrt(n))
    assert np.allclose(imu.gyro.std(axis=0), GYRO_NOISE, rtol=0.03)
    assert np.allclose(imu.mag.mean(axis=0), [MAG_XY, 0.0, MAG_Z], atol=0.05)
    o = np.where(imu.orientation > 180, imu.orientation - 360, imu.orientation)
    assert abs(o.std() / cfg.orientation_sigma_deg - 1) < 0.03
    assert ((imu.orientation >= 0) & (imu.orientation < 360)).all()


def test_a_turning_robot_feels_the_gyro_and_the_centripetal_acceleration():
    cfg = ImuConfig(accel_sigma=(0.0, 0.0, 0.0), gyro_sigma=(0.0, 0.0, 0.0))
    w = np.array([2.0])
    imu = imu_readings(np.zeros(1), w, np.zeros(1), w, np.zeros(1), 0.033, cfg, np.random.default_rng(0))
    assert imu.gyro[0, 2] == 2.0
    ox, oy = cfg.imu_offset
    assert np.allclose(imu.accel[0, :2], [-4.0 * ox, -4.0 * oy])
