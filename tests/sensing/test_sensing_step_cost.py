"""Cheaper sensing steps read the same (issue 28: the rps 2.x examples' run time): :meth:`Sensors.update` casts each
step's rays once, takes the encoders' and the IMU's normal draws in one call and freezes its fresh arrays in place —
and every reading is the one the composition of the public models gives, bit for bit, from the same seed (the models
as ``Sensors`` called them before: true_distances, noisy_distances, encoder_increment, imu_readings,
range_and_bearing, distance_endpoints, in that order).
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.core.ports import ReportsSensors
from swarmdeck.devices import Arena
from swarmdeck.devices.simulated_robots import SimulatedRobots
from swarmdeck.devices.simulator import ArenaConfig, SimulatedArena
from swarmdeck.sensing import DistanceSensorConfig, RangeBearingConfig, SensingConfig, SensorReadings, Sensors
from swarmdeck.sensing.models import (
    body_centres,
    distance_endpoints,
    encoder_increment,
    encoders_and_imu,
    imu_readings,
    noisy_distances,
    range_and_bearing,
    sensor_rays,
    true_distances,
)

FIELDS = ("distances", "origins", "endpoints", "encoders", "accel", "gyro", "mag", "orientation", "leds")
OBSTACLES = np.array([[[-1.0, -0.5], [-1.0, 0.5]], [[0.6, -0.5], [0.6, 0.5]], [[-1.4, 0.9], [1.4, 0.9]]])


class _Reference:
    """The readings as ``Sensors.update`` made them before (one public model call per sensor)."""

    def __init__(self, n: int, config: SensingConfig, rng: np.random.Generator, obstacles: np.ndarray | None) -> None:
        self.n, self.config, self.rng, self.obstacles = n, config, rng, obstacles
        self.params = GritsBotParams()
        self.encoders = np.zeros((n, 2))
        self.v_prev, self.w_prev = np.zeros(n), np.zeros(n)

    def update(self, poses: np.ndarray, v: np.ndarray, w: np.ndarray, dt: float) -> dict:
        cfg = self.config
        vv = np.nan_to_num(np.asarray(v, dtype=float).reshape(self.n), nan=0.0, posinf=0.0, neginf=0.0)
        ww = np.nan_to_num(np.asarray(w, dtype=float).reshape(self.n), nan=0.0, posinf=0.0, neginf=0.0)
        out: dict = dict.fromkeys(FIELDS)
        if cfg.distance is not None:
            true = true_distances(poses, cfg.distance, obstacles=self.obstacles, bounds=DEFAULT_BOUNDS)
            out["distances"] = noisy_distances(true, cfg.distance, self.rng)
            out["origins"] = sensor_rays(poses, cfg.distance)[0]
            out["endpoints"] = distance_endpoints(poses, out["distances"], cfg.distance)
        if cfg.imu is not None:
            self.encoders = self.encoders + encoder_increment(vv, ww, dt, self.params, cfg.imu, self.rng)
            imu = imu_readings(vv, ww, self.v_prev, self.w_prev, poses[:, 2], dt, cfg.imu, self.rng)
            out.update(encoders=self.encoders.astype(np.int64), accel=imu.accel, gyro=imu.gyro, mag=imu.mag,
                       orientation=imu.orientation)
        if cfg.range_bearing is not None:
            out["rb"] = range_and_bearing(poses, cfg.range_bearing, self.rng)
        self.v_prev, self.w_prev = vv, ww
        return out


COMMANDS = st.sampled_from([0.0, 0.1, -0.2, 1.5, math.nan, math.inf, -math.inf, -0.0])


@settings(max_examples=40, deadline=None)
@given(n=st.integers(0, 16), seed=st.integers(0, 2**31 - 1), distance=st.booleans(), walls=st.booleans(),
       obstacles=st.booleans(), imu=st.booleans(), rb=st.booleans(), leds=st.booleans(),
       odd=st.lists(st.tuples(st.integers(0, 15), COMMANDS, COMMANDS), max_size=4),
       bit_generator=st.sampled_from([np.random.PCG64, np.random.MT19937, np.random.Philox]))
def test_the_readings_are_the_public_models_bits(n, seed, distance, walls, obstacles, imu, rb, leds, odd,
                                                   bit_generator):
    kwargs: dict = {"leds": leds, "distance": DistanceSensorConfig(walls=walls) if distance else None,
                    "range_bearing": RangeBearingConfig() if rb else None}
    if not imu:
        kwargs["imu"] = None
    config = SensingConfig(**kwargs)
    obst = OBSTACLES if obstacles else None
    sensors = Sensors(n, config, rng=np.random.Generator(bit_generator(seed)), obstacles=obst)
    reference = _Reference(n, config, np.random.Generator(bit_generator(seed)), obst)
    rng = np.random.default_rng(seed + 1)
    poses = np.column_stack((rng.uniform(-1.5, 1.5, (n, 2)), rng.uniform(-math.pi, math.pi, n)))
    for step in range(3):
        v, w = rng.uniform(-0.2, 0.2, n), rng.uniform(-3.0, 3.0, n)
        for i, a, b in odd:  # non-finite and signed-zero commands read as 0
            if i < n:
                v[i], w[i] = a, b
        poses = poses + rng.normal(0.0, 0.02, poses.shape)
        got = sensors.update(poses, v, w, 0.033)
        want = reference.update(poses, v, w, 0.033)
        for name in FIELDS[:-1]:
            a, b = getattr(got, name), want[name]
            assert (a is None) == (b is None), name
            if a is not None:
                assert a.dtype == b.dtype and a.shape == b.shape, name
                assert np.array_equal(a, b, equal_nan=True), (name, step, a, b)
                assert not a.flags.writeable, name
        if rb:
            for part in ("i", "j", "range", "bearing"):
                assert np.array_equal(getattr(got.range_bearing, part), getattr(want["rb"], part)), part
    # the next draw of either generator is the same: the same number of draws, in the same order
    assert sensors.rng.random() == reference.rng.random()


@settings(max_examples=30, deadline=None)
@given(n=st.integers(1, 12), seed=st.integers(0, 2**31 - 1), encoders=st.booleans())
def test_one_draw_for_the_encoders_and_the_imu_gives_the_separate_models_bits(n, seed, encoders):
    rng = np.random.default_rng(seed)
    v, w, v0, w0 = (rng.uniform(-0.3, 0.3, n) for _ in range(4))
    theta = rng.uniform(-4.0, 4.0, n)
    params, cfg = GritsBotParams(), SensingConfig().imu
    assert cfg is not None
    one, separate = np.random.default_rng(seed + 7), np.random.default_rng(seed + 7)
    increment, imu = encoders_and_imu(v, w, v0, w0, theta, 0.033, params, cfg, one, encoders=encoders)
    if encoders:
        assert np.array_equal(increment, encoder_increment(v, w, 0.033, params, cfg, separate))
    else:
        assert increment is None
    want = imu_readings(v, w, v0, w0, theta, 0.033, cfg, separate)
    for name in ("accel", "gyro", "mag", "orientation"):
        assert np.array_equal(getattr(imu, name), getattr(want, name)), name
    assert one.random() == separate.random()


def test_the_readings_before_the_first_step_are_unchanged():
    cfg = SensingConfig(distance=DistanceSensorConfig())
    first = Sensors(3, cfg, rng=np.random.default_rng(5)).first(np.array([[0.0, 0.0, 0.0], [0.5, 0, 1], [-1, 0, 2]]))
    assert first.distances is not None and np.isnan(first.distances).all()
    assert first.endpoints is not None and np.isnan(first.endpoints).all()
    assert first.encoders is not None and not first.encoders.any()
    rng = np.random.default_rng(5)
    want = imu_readings(np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), np.array([0.0, 1, 2]), 1.0, cfg.imu, rng)
    assert first.accel is not None and np.array_equal(first.accel, want.accel)
    assert first.orientation is not None and np.array_equal(first.orientation, want.orientation)
    with pytest.raises(ValueError, match="read-only"):
        first.accel[0, 0] = 1.0


def _sensor_rays_as_composed(poses: np.ndarray, config: DistanceSensorConfig) -> tuple[np.ndarray, np.ndarray]:
    """sensor_rays as it was written before: the body centres, then each sensor's mount turned by the heading."""
    s = config.pose_array()
    th = poses[:, 2:3]
    c, sn = np.cos(th), np.sin(th)
    centre = body_centres(poses, config.body_offset)
    ox = centre[:, 0:1] + c * s[None, :, 0] - sn * s[None, :, 1]
    oy = centre[:, 1:2] + sn * s[None, :, 0] + c * s[None, :, 1]
    heading = th + s[None, :, 2]
    return np.stack((ox, oy), axis=-1), np.stack((np.cos(heading), np.sin(heading)), axis=-1)


@settings(max_examples=30, deadline=None)
@given(n=st.integers(0, 20), seed=st.integers(0, 2**31 - 1), scale=st.sampled_from([1e-3, 1.0, 1e3]))
def test_the_sensor_rays_are_the_body_centres_and_mounts_bits(n, seed, scale):
    rng = np.random.default_rng(seed)
    poses = np.column_stack((rng.uniform(-scale, scale, (n, 2)), rng.uniform(-10.0, 10.0, n)))
    cfg = DistanceSensorConfig()
    got, want = sensor_rays(poses, cfg), _sensor_rays_as_composed(poses, cfg)
    for a, b in zip(got, want):
        assert a.shape == b.shape and np.array_equal(a, b)


class _Blocked(SimulatedRobots):
    """Robots that block the protocol's method (typing's protocol check: not a ReportsSensors)."""

    sensor_readings = None


class _Reporting(SimulatedRobots):
    def sensor_readings(self) -> SensorReadings:
        return SensorReadings(distances=np.full((self.sim.n_robots, 7), 0.25))


@pytest.mark.parametrize("kind", [SimulatedRobots, _Blocked, _Reporting])
def test_the_arena_takes_reported_readings_exactly_from_reports_sensors_ports(kind):
    """The Arena's step asks the robots for readings without typing's protocol check (≈ 20 µs a step), and decides
    as it does: a port reports iff it is a ReportsSensors."""
    ic = np.array([[-0.5, 0.0, 0.0], [0.5, 0.0, np.pi]])
    robots = kind(sim=SimulatedArena(None, ic, config=ArenaConfig(seed=1)))
    arena = Arena(backend=robots, sensing=SensingConfig(distance=DistanceSensorConfig()))
    arena.step()
    reported = bool((arena.sense().distances == 0.25).all())
    assert reported == isinstance(robots, ReportsSensors)
    assert reported == (kind is _Reporting)
