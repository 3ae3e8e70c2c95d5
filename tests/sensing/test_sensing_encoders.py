"""Wheel encoder counts against the integrated wheel speeds (REFERENCE.md §15: 28 counts/rev, gear 100.37, noise
σ 0.25·√counts per step): directly, and through an Arena whose robots drive a known path."""
from __future__ import annotations

import math

import numpy as np

from swarmdeck.core.constants import ENCODER_COUNTS_PER_REV, MOTOR_GEAR_RATIO
from swarmdeck.core.kinematics import GritsBotParams, unicycle_to_wheels
from swarmdeck.devices import Arena
from swarmdeck.devices.simulator import ArenaConfig
from swarmdeck.sensing import ImuConfig, SensingConfig, encoder_increment

COUNTS_PER_RAD = ENCODER_COUNTS_PER_REV * MOTOR_GEAR_RATIO / (2 * math.pi)


def test_counts_sum_to_the_integrated_wheel_angle_within_the_noise():
    params, cfg, dt, steps = GritsBotParams(), ImuConfig(), 0.033, 300
    v = np.array([0.1, 0.0, 0.05, -0.08])
    w = np.array([0.0, 1.5, -0.7, 0.4])
    rng = np.random.default_rng(11)
    total = sum(encoder_increment(v, w, dt, params, cfg, rng) for _ in range(steps))
    right, left = unicycle_to_wheels(v, w, params)
    expected = np.column_stack((left, right)) * dt * steps * COUNTS_PER_RAD
    per_step = np.maximum(np.abs(expected / steps), 1.0)
    sigma = cfg.encoder_sigma * np.sqrt(per_step * steps) + 0.5 * math.sqrt(steps)  # noise + rounding
    assert (np.abs(total - expected) <= 5 * sigma).all(), (total, expected)
    assert np.array_equal(total, np.round(total))


def test_an_arena_robot_driving_straight_counts_the_distance_it_travelled():
    arena = Arena(initial_conditions=np.array([[-1.0, 0.0, 0.0]]), config=ArenaConfig(seed=4),
                  sensing=SensingConfig(), safety=False)
    assert np.array_equal(arena.sense().encoders, [[0, 0]])
    for _ in range(150):
        arena.set_unicycle(np.array([0.1]), np.array([0.0]))
        arena.step()
    travelled = arena.poses()[0, 0] + 1.0
    counts = arena.sense().encoders[0]
    assert counts.dtype == np.int64
    wheel_angle = travelled / arena.params.wheel_radius
    noise = ImuConfig().encoder_sigma * math.sqrt(wheel_angle * COUNTS_PER_RAD) + 0.5 * math.sqrt(150)
    assert (np.abs(counts - wheel_angle * COUNTS_PER_RAD) <= 5 * noise + 1).all(), (counts, wheel_angle * COUNTS_PER_RAD)
