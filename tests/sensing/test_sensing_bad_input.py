"""Bad sensing input gets a clear error naming what was wrong (issue 28, "Bad input"): a sensor pose outside the
body, a negative or NaN range, bad noise probabilities, NaN obstacle coordinates, LED colours out of range."""
from __future__ import annotations

import math

import numpy as np
import pytest

from swarmdeck.core.errors import SwarmdeckError
from swarmdeck.sensing import (
    DistanceSensorConfig,
    ImuConfig,
    RangeBearingConfig,
    SensingConfig,
    SensingConfigError,
    Sensors,
    true_distances,
)


def test_a_sensor_pose_outside_the_body_is_refused_by_name():
    poses = ((0.05, 0.0, 0.0), (0.2, 0.0, 0.0))
    with pytest.raises(SensingConfigError, match=r"poses\[1\].*outside the body.*0\.2000 m"):
        DistanceSensorConfig(poses=poses)


@pytest.mark.parametrize("value", [-1.0, 0.0, math.nan, math.inf, "1.2", True])
def test_a_negative_zero_nan_or_non_number_range_is_refused(value):
    with pytest.raises(SensingConfigError, match="DistanceSensorConfig.max_range must be > 0 m"):
        DistanceSensorConfig(max_range=value)


@pytest.mark.parametrize("field", ["dropout", "outlier", "error"])
@pytest.mark.parametrize("value", [-0.1, 1.5, math.nan])
def test_probabilities_outside_0_1_are_refused(field, value):
    with pytest.raises(SensingConfigError, match=f"DistanceSensorConfig.{field} must be in"):
        DistanceSensorConfig(**{field: value})


def test_other_bad_configuration_is_named():
    with pytest.raises(SensingConfigError, match="RangeBearingConfig.radius"):
        RangeBearingConfig(radius=-0.5)
    with pytest.raises(SensingConfigError, match="RangeBearingConfig.fov"):
        RangeBearingConfig(fov=7.0)
    with pytest.raises(SensingConfigError, match=r"ImuConfig.accel_sigma\[2\]"):
        ImuConfig(accel_sigma=(0.1, 0.1, math.nan))
    with pytest.raises(SensingConfigError, match="poses\\[0\\] must be \\(x, y, heading\\)"):
        DistanceSensorConfig(poses=((0.0, 0.0),))  # type: ignore[arg-type]
    with pytest.raises(SensingConfigError, match="SensingConfig.distance must be a DistanceSensorConfig"):
        SensingConfig(distance=1.2)  # type: ignore[arg-type]


def test_errors_are_value_errors_and_swarmdeck_errors():
    assert issubclass(SensingConfigError, ValueError) and issubclass(SensingConfigError, SwarmdeckError)


def test_bad_obstacles_and_poses_are_named():
    cfg = DistanceSensorConfig()
    pose = np.zeros((1, 3))
    with pytest.raises(SensingConfigError, match=r"segment\(s\) \[1\] have NaN"):
        true_distances(pose, cfg, obstacles=np.array([[[0, 0], [1, 0]], [[0, math.nan], [1, 1]]]))
    with pytest.raises(SensingConfigError, match=r"shape \(M, 2, 2\)"):
        true_distances(pose, cfg, obstacles=np.zeros((2, 3)))
    with pytest.raises(SensingConfigError, match=r"robot\(s\) \[0\] are NaN"):
        true_distances(np.array([[math.nan, 0, 0]]), cfg)


def test_led_colours_are_checked():
    s = Sensors(2, SensingConfig(), rng=np.random.default_rng(0))
    with pytest.raises(SensingConfigError, match=r"shape \(2, 3\)"):
        s.set_leds(np.zeros((3, 3)))
    with pytest.raises(SensingConfigError, match=r"in \[0, 255\]"):
        s.set_leds(np.array([[0, 0, 300], [0, 0, 0]]))
    with pytest.raises(SensingConfigError, match="robot indices 0..1"):
        s.set_leds(np.array([[1, 2, 3]]), ids=[5])
    s.set_leds(np.array([[1.0, 0.0, 0.5]]), ids=[1])  # rps's [0, 1] colours are scaled
    assert s.first(np.zeros((2, 3))).leds.tolist() == [[0, 0, 0], [255, 0, 128]]
    with pytest.raises(SensingConfigError, match="rng must be a numpy.random.Generator"):
        Sensors(2, SensingConfig(), rng=np.random)  # type: ignore[arg-type]
