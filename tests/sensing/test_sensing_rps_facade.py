"""rps 2.0's sensor API on the facade (REFERENCE.md §15): ``use_distance_sensors=True``, ``obstacles``, the getters'
shapes and behaviour, ``get_distances()`` without the flag (rps 2.0: NaN, and the facade names the flag), LEDs."""
from __future__ import annotations

import math

import numpy as np
import pytest

from swarmdeck.core.constants import TOF_BODY_OFFSET
from swarmdeck.devices.rps import rps_aliases
from swarmdeck.devices.rps.sensors import SensorsDisabledError

WALL = np.array([[[0.5, -0.8], [0.5, 0.8]]])


def robotarium(**kw):
    with rps_aliases():
        import rps.robotarium

        return rps.robotarium.Robotarium(show_figure=False, sim_in_real_time=False, **kw)


def test_distances_through_the_2x_api_see_an_obstacle_ahead():
    ic = np.array([[0.0], [0.0], [0.0]])
    r = robotarium(number_of_robots=1, initial_conditions=ic, use_distance_sensors=True, obstacles=WALL)
    assert r.get_distances().shape == (7, 1) and np.isnan(r.get_distances()).all()  # NaN until the first step
    r.get_poses()
    r.set_velocities(np.arange(1), np.zeros((2, 1)))
    r.step()
    d = r.get_distances()
    assert d.shape == (7, 1)
    front = d[3, 0]
    true = 0.5 - TOF_BODY_OFFSET - 0.05
    assert front == -1.0 or abs(front - true) < 0.2  # a dropout, an outlier or within the noise
    e = r.get_distance_endpoints()
    assert e.shape == (2, 7, 1)
    if front >= 0:
        assert math.isclose(e[0, 3, 0], TOF_BODY_OFFSET + 0.05 + front, abs_tol=1e-9)
    assert np.isnan(e[:, 1, 0]).all()  # the left sensor sees nothing: NaN, as rps 2.0
    assert r._distance_sensors_enabled


def test_without_use_distance_sensors_distances_are_nan_with_a_warning_and_endpoints_fail():
    r = robotarium(number_of_robots=2)
    with pytest.warns(RuntimeWarning, match="use_distance_sensors=True"):
        d = r.get_distances()
    assert d.shape == (7, 2) and np.isnan(d).all()
    with pytest.raises(SensorsDisabledError, match="use_distance_sensors=True") as err:
        r.get_distance_endpoints()
    assert isinstance(err.value, AttributeError)  # rps 2.0 fails there with an AttributeError


def test_a_non_bool_flag_and_bad_obstacles_are_named():
    with pytest.raises(TypeError, match="use_distance_sensors must be True or False"):
        robotarium(number_of_robots=1, use_distance_sensors=1)
    with pytest.raises(ValueError, match=r"obstacles must have shape \(M, 2, 2\)"):
        robotarium(number_of_robots=1, obstacles=np.zeros((3, 2)))


def test_encoders_imu_and_leds_have_rps_shapes():
    r = robotarium(number_of_robots=3, rps_semantics=True,  # no safety filter: the commands run as they are
                   initial_conditions=np.array([[-1.0, 0.0, 1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]))
    assert r.get_encoders().shape == (2, 3) and r.get_encoders().dtype == np.int32
    for _ in range(20):
        r.get_poses()
        r.set_velocities(np.arange(3), np.array([[0.1, 0.0, -0.05], [0.0, 1.0, 0.0]]))
        r.step()
    enc = r.get_encoders()
    assert (enc[:, 0] > 0).all() and (enc[:, 2] < 0).all()  # forward turns both wheels forward, backward back
    assert enc[1, 1] > 0 > enc[0, 1]  # turning left on the spot: right wheel forward, left back
    assert r.get_accelerations().shape == r.get_gyros().shape == r.get_magnetic_fields().shape == (3, 3)
    assert abs(r.get_accelerations()[2].mean() + 9.81) < 0.2
    assert r.get_orientations().shape == (3,)
    assert ((r.get_orientations() >= 0) & (r.get_orientations() < 360)).all()
    r.set_leds([0, 2], np.array([[255, 0], [0, 0], [0, 255]]))
    assert r._leds.T.tolist() == [[255, 0, 0], [0, 0, 0], [0, 0, 255]]
    assert r.arena.sense().leds[2].tolist() == [0, 0, 255]


def test_dead_reckoning_from_the_encoders_follows_the_robot_as_in_rps_2_examples():
    """rps 2.0's dead_reckoning example's arithmetic: wheel travel from count deltas with r.WHEEL_RADIUS,
    r.BASE_LENGTH and r.ENCODER_COUNTS_PER_REVOLUTION · r.MOTOR_GEAR_RATIO tracks the true pose."""
    ic = np.array([[-0.5], [0.0], [0.0]])
    r = robotarium(number_of_robots=1, initial_conditions=ic)
    per_rev = r.ENCODER_COUNTS_PER_REVOLUTION * r.MOTOR_GEAR_RATIO
    est = ic[:, 0].copy()
    prev = r.get_encoders().astype(float)[:, 0]
    r.get_poses()
    r.set_velocities(np.arange(1), np.array([[0.1], [0.6]]))
    r.step()
    for _ in range(200):
        x = r.get_poses()
        enc = r.get_encoders().astype(float)[:, 0]
        d_left, d_right = (enc - prev) / per_rev * 2 * np.pi * r.WHEEL_RADIUS
        prev = enc
        d_c, d_th = (d_left + d_right) / 2, (d_right - d_left) / r.BASE_LENGTH
        est += [d_c * np.cos(est[2] + d_th / 2), d_c * np.sin(est[2] + d_th / 2), d_th]
        r.set_velocities(np.arange(1), np.array([[0.1], [0.6]]))
        r.step()
    x = r.get_poses()[:, 0]
    enc = r.get_encoders().astype(float)[:, 0]
    d_left, d_right = (enc - prev) / per_rev * 2 * np.pi * r.WHEEL_RADIUS
    d_c, d_th = (d_left + d_right) / 2, (d_right - d_left) / r.BASE_LENGTH
    est += [d_c * np.cos(est[2] + d_th / 2), d_c * np.sin(est[2] + d_th / 2), d_th]
    assert np.hypot(*(est[:2] - x[:2])) < 0.05, (est, x)
    assert abs(np.angle(np.exp(1j * (est[2] - x[2])))) < 0.1
