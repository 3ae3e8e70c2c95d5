"""The sensor models: ToF distances, range and bearing, wheel encoders and the IMU (REFERENCE.md §15, §16).

Pure functions of the poses and commands; every random draw comes from the ``numpy.random.Generator`` passed in
(the same seed, the same readings), and the number of draws depends only on the array shapes. Arrays have one row
per robot: poses ``(N, 3)`` ``[x, y, θ]`` (m, rad), commands ``v`` (m/s), ``w`` (rad/s) ``(N,)``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.bounds import Bounds
from swarmdeck.core.constants import GRAVITY
from swarmdeck.core.graphs import pairs_within
from swarmdeck.core.kinematics import UnicycleParams, unicycle_to_wheels, wrap_angle
from swarmdeck.sensing.config import DistanceSensorConfig, ImuConfig, RangeBearingConfig, SensingConfigError
from swarmdeck.sensing.geometry import cast_sensor_rays, check_segments, segments_and_walls

__all__ = ["ImuReadings", "RangeBearing", "check_sensing_poses", "distance_endpoints", "distances_along",
           "encoder_increment", "encoders_and_imu", "endpoints_along", "imu_readings", "noisy_distances",
           "range_and_bearing", "sensor_rays", "true_distances"]

FloatArray = NDArray[np.float64]


def check_sensing_poses(poses: ArrayLike) -> FloatArray:
    """``poses`` as a finite ``(N, 3)`` float array; raises :class:`SensingConfigError` naming what is wrong."""
    arr = np.asarray(poses, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise SensingConfigError(f"poses must have shape (N, 3) [x, y, theta], got {arr.shape}")
    if not np.isfinite(arr).all():
        raise SensingConfigError(f"poses of robot(s) {np.flatnonzero(~np.isfinite(arr).all(axis=1)).tolist()} "
                                 "are NaN or infinite")
    return arr


def body_centres(poses: FloatArray, offset: float) -> FloatArray:
    """``(N, 2)`` centres of the bodies ``offset`` m ahead of the axles."""
    th = poses[:, 2]
    return poses[:, :2] + offset * np.column_stack((np.cos(th), np.sin(th)))


def sensor_rays(poses: ArrayLike, config: DistanceSensorConfig) -> tuple[FloatArray, FloatArray]:
    """Each robot's sensor rays: origins ``(N, K, 2)`` m and unit directions ``(N, K, 2)`` in the arena frame."""
    p = check_sensing_poses(poses)
    s = config.pose_array()  # (K, 3)
    th = p[:, 2:3]  # (N, 1)
    c, sn = np.cos(th), np.sin(th)
    offset = config.body_offset  # the body centre: body_centres' arithmetic, with these cos and sin
    n, k = len(p), len(s)
    origins = np.empty((n, k, 2))
    origins[..., 0] = (p[:, 0:1] + offset * c) + c * s[None, :, 0] - sn * s[None, :, 1]
    origins[..., 1] = (p[:, 1:2] + offset * sn) + sn * s[None, :, 0] + c * s[None, :, 1]
    heading = th + s[None, :, 2]
    directions = np.empty((n, k, 2))
    directions[..., 0] = np.cos(heading)
    directions[..., 1] = np.sin(heading)
    return origins, directions


def true_distances(poses: ArrayLike, config: DistanceSensorConfig, *, obstacles: ArrayLike | None = None,
                   bounds: Bounds | None = None) -> FloatArray:
    """Noise-free ``(N, K)`` distance, m, from each sensor to the first thing its ray meets: another robot's body
    (a circle of ``body_radius`` centred ``body_offset`` ahead of its axle), an obstacle segment ``(M, 2, 2)`` or —
    when ``config.walls`` and ``bounds`` are given — a wall; inf where nothing lies within ``max_range``."""
    p = check_sensing_poses(poses)
    if len(p) == 0:
        return np.empty((0, config.n_sensors))
    origins, directions = sensor_rays(p, config)
    return distances_along(p, origins, directions, config, check_segments(obstacles), bounds)


def distances_along(poses: FloatArray, origins: FloatArray, directions: FloatArray, config: DistanceSensorConfig,
                    segments: FloatArray, bounds: Bounds | None) -> FloatArray:
    """:func:`true_distances` of checked ``poses`` ``(N, 3)`` (N ≥ 1) along their :func:`sensor_rays`
    ``origins``, ``directions`` ``(N, K, 2)`` against checked ``segments`` ``(M, 2, 2)``
    (:func:`~swarmdeck.sensing.geometry.check_segments`): for a caller that has the rays already. ``(N, K)`` m."""
    n, k = len(poses), config.n_sensors
    if n < 2:  # no other body to hit (cast_sensor_rays' answer, without its set-up)
        t = np.full((n, k), np.inf)
    else:
        t = cast_sensor_rays(body_centres(poses, config.body_offset), poses[:, 2], origins, directions,
                             config.pose_array()[:, 2], config.max_range, config.body_radius)
    rest = segments_and_walls(np.full(n * k, np.inf), origins.reshape(-1, 2), directions.reshape(-1, 2),
                              config.max_range, segments, bounds if config.walls else None)
    return np.minimum(t, rest.reshape(n, k))


def noisy_distances(true: ArrayLike, config: DistanceSensorConfig, rng: np.random.Generator) -> FloatArray:
    """rps 2.0's reading model over true distances ``(N, K)`` (inf: nothing in range): a hit closer than
    ``max_range`` is dropped (−1) with probability ``dropout``; a kept one is an outlier, uniform on
    [0, max_range], with probability ``outlier``; otherwise ``d + error·d·ε`` clipped to [0, max_range]. Nothing
    in range reads −1. Returns ``(N, K)`` m."""
    d = np.asarray(true, dtype=float)
    rmax = config.max_range
    drop = rng.random(d.shape) < config.dropout
    outlier = rng.random(d.shape) < config.outlier
    wild = rng.uniform(0.0, rmax, d.shape)
    eps = rng.standard_normal(d.shape)
    seen = d < rmax
    with np.errstate(invalid="ignore"):
        noisy = np.clip(d + config.error * d * eps, 0.0, rmax)
    out = np.where(outlier, wild, noisy)
    return np.where(seen & ~drop, out, -1.0)


def distance_endpoints(poses: ArrayLike, readings: ArrayLike, config: DistanceSensorConfig) -> FloatArray:
    """Where each reading ends: ``(N, K, 2)`` m, NaN where the reading is −1 (nothing) or NaN."""
    origins, directions = sensor_rays(poses, config)
    return endpoints_along(origins, directions, readings)


def endpoints_along(origins: FloatArray, directions: FloatArray, readings: ArrayLike) -> FloatArray:
    """:func:`distance_endpoints` along rays the caller has: ``origins``, ``directions`` ``(N, K, 2)``,
    ``readings`` ``(N, K)`` m. ``(N, K, 2)`` m, NaN where the reading is −1 or NaN."""
    r = np.asarray(readings, dtype=float)
    with np.errstate(invalid="ignore"):
        ok = (r >= 0.0)[..., None]
    return np.where(ok, origins + np.where(ok, r[..., None], 0.0) * directions, np.nan)


@dataclass(frozen=True)
class RangeBearing:
    """Range-and-bearing measurements, one row per (observer, neighbour) pair, sorted by observer then neighbour.

    Attributes:
        i: ``(P,)`` observing robot (row index).
        j: ``(P,)`` observed neighbour (row index).
        range: ``(P,)`` measured centre distance, m.
        bearing: ``(P,)`` measured direction of j in i's body frame, rad in (−π, π] (0: straight ahead).
    """

    i: NDArray[np.intp]
    j: NDArray[np.intp]
    range: FloatArray
    bearing: FloatArray

    def of(self, robot: int) -> tuple[NDArray[np.intp], FloatArray, FloatArray]:
        """``(neighbours, ranges, bearings)`` robot ``robot`` measured."""
        lo, hi = np.searchsorted(self.i, [robot, robot + 1])
        return self.j[lo:hi], self.range[lo:hi], self.bearing[lo:hi]


def range_and_bearing(poses: ArrayLike, config: RangeBearingConfig, rng: np.random.Generator) -> RangeBearing:
    """Range and bearing from every robot to each neighbour within ``config.radius`` (centre to centre) and inside
    its field of view, with Gaussian noise and dropout (:func:`~swarmdeck.core.graphs.pairs_within` finds the pairs). See :class:`RangeBearing`."""
    p = check_sensing_poses(poses)
    empty = RangeBearing(np.empty(0, np.intp), np.empty(0, np.intp), np.empty(0), np.empty(0))
    if len(p) < 2:
        return empty
    pairs = pairs_within(p[:, :2], config.radius)
    i = np.concatenate((pairs[:, 0], pairs[:, 1]))
    j = np.concatenate((pairs[:, 1], pairs[:, 0]))
    order = np.lexsort((j, i))
    i, j = i[order], j[order]
    rel = p[j, :2] - p[i, :2]
    dist = np.hypot(rel[:, 0], rel[:, 1])
    bearing = wrap_angle(np.arctan2(rel[:, 1], rel[:, 0]) - p[i, 2])
    m = len(i)
    r_noise = rng.standard_normal(m)
    b_noise = rng.standard_normal(m)
    kept = rng.random(m) >= config.dropout
    if config.fov < 2 * np.pi:
        kept &= np.abs(bearing) <= config.fov / 2
    return RangeBearing(i[kept], j[kept], np.maximum(dist + config.range_sigma * r_noise, 0.0)[kept],
                        wrap_angle(bearing + config.bearing_sigma * b_noise)[kept])


def encoder_increment(v: ArrayLike, w: ArrayLike, dt: float, params: UnicycleParams, config: ImuConfig,
                      rng: np.random.Generator) -> FloatArray:
    """One step's encoder counts ``(N, 2)`` [left, right] while the wheels turn at the speeds of ``(v, w)`` for
    ``dt`` s: ω_wheel·dt·counts_per_rev·gear_ratio/2π, plus N(0, (σ·√max(|Δ|, 1))²), rounded (rps 2.0's model)."""
    right, left = unicycle_to_wheels(v, w, params)
    delta = np.column_stack((left, right)) * dt * config.counts_per_radian
    sigma = config.encoder_sigma * np.sqrt(np.maximum(np.abs(delta), 1.0))
    return np.round(delta + sigma * rng.standard_normal(delta.shape))


@dataclass(frozen=True)
class ImuReadings:
    """One step's IMU: accel ``(N, 3)`` m/s² (body x, y, z; z reads −g at rest), gyro ``(N, 3)`` rad/s,
    mag ``(N, 3)`` µT, orientation ``(N,)`` degrees in [0, 360)."""

    accel: FloatArray
    gyro: FloatArray
    mag: FloatArray
    orientation: FloatArray


def imu_readings(v: ArrayLike, w: ArrayLike, v_prev: ArrayLike, w_prev: ArrayLike, theta: ArrayLike, dt: float,
                 config: ImuConfig, rng: np.random.Generator) -> ImuReadings:
    """rps 2.0's IMU models: the accelerometer at ``imu_offset`` sees the linear and tangential acceleration of
    the commands' change over ``dt`` plus the centripetal part and gravity; the gyro ω about z; the magnetometer
    a fixed field turned by θ; the orientation θ in degrees. Each with its Gaussian noise (``config``)."""
    v, w = np.asarray(v, dtype=float), np.asarray(w, dtype=float)
    th = np.asarray(theta, dtype=float)
    n = len(v)
    lin = (v - np.asarray(v_prev, dtype=float)) / dt
    ang = (w - np.asarray(w_prev, dtype=float)) / dt
    ox, oy = config.imu_offset
    zero = np.zeros(n)
    accel = np.column_stack((lin - ang * oy - w * w * ox, ang * ox - w * w * oy, np.full(n, -GRAVITY)))
    accel = accel + np.asarray(config.accel_sigma) * rng.standard_normal((n, 3))
    gyro = np.column_stack((zero, zero, w)) + np.asarray(config.gyro_sigma) * rng.standard_normal((n, 3))
    mag = np.column_stack((config.mag_xy * np.cos(th), -config.mag_xy * np.sin(th), np.full(n, config.mag_z)))
    mag = mag + np.asarray(config.mag_sigma) * rng.standard_normal((n, 3))
    orientation = np.mod(np.degrees(th) + config.orientation_sigma_deg * rng.standard_normal(n), 360.0)
    return ImuReadings(accel, gyro, mag, orientation)


def encoders_and_imu(v: FloatArray, w: FloatArray, v_prev: FloatArray, w_prev: FloatArray, theta: FloatArray,
                     dt: float, params: UnicycleParams, config: ImuConfig, rng: np.random.Generator, *,
                     encoders: bool) -> tuple[FloatArray | None, ImuReadings]:
    """:func:`encoder_increment` (when ``encoders``; else None) then :func:`imu_readings`, for float arrays ``(N,)``
    — the same readings, bit for bit (tests/sensing/test_sensing_step_cost.py), for a fraction of the calls: their
    normal draws are taken in one call (a Generator fills an array draw by draw, so 12N normals are the 2N + 3N +
    3N + 3N + N of the separate calls, in their order) and the accelerometer, gyro and magnetometer are one
    ``(3, N, 3)`` array (each a read-only view once the caller freezes it)."""
    n = len(v)
    z = rng.standard_normal((12 if encoders else 10) * n)
    increment = None
    at = 0
    if encoders:
        right, left = unicycle_to_wheels(v, w, params)
        delta = np.column_stack((left, right)) * dt * config.counts_per_radian
        sigma = config.encoder_sigma * np.sqrt(np.maximum(np.abs(delta), 1.0))
        increment = np.round(delta + sigma * z[:2 * n].reshape(n, 2))
        at = 2 * n
    lin = (v - v_prev) / dt
    ang = (w - w_prev) / dt
    ox, oy = config.imu_offset
    base = np.empty((3, n, 3))
    base[0, :, 0] = lin - ang * oy - w * w * ox
    base[0, :, 1] = ang * ox - w * w * oy
    base[0, :, 2] = -GRAVITY
    base[1, :, :2] = 0.0
    base[1, :, 2] = w
    base[2, :, 0] = config.mag_xy * np.cos(theta)
    base[2, :, 1] = -config.mag_xy * np.sin(theta)
    base[2, :, 2] = config.mag_z
    sigmas = np.array((config.accel_sigma, config.gyro_sigma, config.mag_sigma), dtype=float)[:, None, :]
    three = base + sigmas * z[at:at + 9 * n].reshape(3, n, 3)
    orientation = np.mod(np.degrees(theta) + config.orientation_sigma_deg * z[at + 9 * n:], 360.0)
    return increment, ImuReadings(three[0], three[1], three[2], orientation)
