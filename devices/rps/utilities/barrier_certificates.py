"""rps.utilities.barrier_certificates backed by swarmdeck's barrier QP (clarabel, status checked).

Unlike rps: the caller's arrays are never normalised in place, there is no
30-robot preallocation, the *solution* is speed-bounded, and a failed solve
returns zeros (robots stop) instead of an unconverged iterate.
"""
from __future__ import annotations

import numpy as np

from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.core.constants import AXLE_LENGTH, MAX_LINEAR_SPEED, MAX_WHEEL_SPEED, SAFETY_DISTANCE, WHEEL_RADIUS
from swarmdeck.core.kinematics import lookahead_points, si_to_unicycle, unicycle_to_si
from swarmdeck.devices.rps.utilities.transformations import *  # noqa: F401,F403 - rps's module re-exports them
from swarmdeck.devices.rps.utilities.transformations import __all__ as _TRANSFORMATIONS
from swarmdeck.safety import BarrierConfig, SafetyFilter
from swarmdeck.safety.qp_clarabel import project_onto_polytope

_OPEN = (-1e6, 1e6, -1e6, 1e6)  # "no walls" for the variants without a boundary


def _boundary(points) -> tuple[float, float, float, float]:
    b = np.asarray(points, dtype=float).reshape(-1)
    if b.shape != (4,):
        raise ValueError(f"boundary_points must be [x_min, x_max, y_min, y_max], got shape {b.shape}")
    return (float(b[0]), float(b[1]), float(b[2]), float(b[3]))


def _si(barrier_gain, safety_radius, magnitude_limit, bounds):
    config = BarrierConfig(safety_distance=safety_radius, gamma=barrier_gain, max_speed=magnitude_limit, bounds=bounds)
    made: list[SafetyFilter] = []  # the filter, built on the first call: it knows the robot count then

    def f(dxi, x):
        x = np.asarray(x, dtype=float)
        if not made:
            made.append(SafetyFilter(config, robots=x.shape[-1] if x.ndim == 2 else None))
        safe, _ = made[0].filter(x[:2].T, np.asarray(dxi, dtype=float).T)
        return safe.T

    return f


def create_single_integrator_barrier_certificate(barrier_gain: float = 100, safety_radius: float = SAFETY_DISTANCE,
                                                 magnitude_limit: float = MAX_LINEAR_SPEED):
    """f(dxi (2, N), x (2, N)) → safe (2, N), pairwise constraints only."""
    return _si(barrier_gain, safety_radius, magnitude_limit, _OPEN)


def create_single_integrator_barrier_certificate_with_boundary(barrier_gain: float = 100, safety_radius: float = SAFETY_DISTANCE,
                                                               magnitude_limit: float = MAX_LINEAR_SPEED,
                                                               boundary_points=np.array(DEFAULT_BOUNDS)):
    """f(dxi (2, N), x (2, N)) → safe (2, N), with the arena walls."""
    return _si(barrier_gain, safety_radius, magnitude_limit, _boundary(boundary_points))


def _uni(barrier_gain, safety_radius, projection_distance, magnitude_limit, bounds):
    si = _si(barrier_gain, safety_radius + projection_distance, magnitude_limit, bounds)

    def f(dxu, x):
        poses = np.asarray(x, dtype=float).T
        dxu = np.asarray(dxu, dtype=float)
        pts = lookahead_points(poses, projection_distance).T
        u = unicycle_to_si(poses, dxu[0], dxu[1], projection_distance).T
        v, w = si_to_unicycle(poses, si(u, pts).T, projection_distance)
        return np.vstack((v, w))

    return f


def create_unicycle_barrier_certificate(barrier_gain: float = 100, safety_radius: float = 0.12,
                                        projection_distance: float = 0.05, magnitude_limit: float = MAX_LINEAR_SPEED):
    """f(dxu (2, N), x (3, N)) → safe (2, N) [v; ω], barrier on the look-ahead points (radius r + ℓ, as rps)."""
    return _uni(barrier_gain, safety_radius, projection_distance, magnitude_limit, _OPEN)


def create_unicycle_barrier_certificate_with_boundary(barrier_gain: float = 100, safety_radius: float = 0.12,
                                                      projection_distance: float = 0.05, magnitude_limit: float = MAX_LINEAR_SPEED,
                                                      boundary_points=np.array(DEFAULT_BOUNDS)):
    """As :func:`create_unicycle_barrier_certificate`, with the arena walls."""
    return _uni(barrier_gain, safety_radius, projection_distance, magnitude_limit, _boundary(boundary_points))


def _unicycle_dd(barrier_gain, safety_radius, projection_distance, wheel_vel_limit, base_length, wheel_radius,
                 disturbance, bounds):
    from swarmdeck.safety import UnicycleParams, UnicycleSafetyFilter

    if not (np.isfinite(disturbance) and disturbance >= 0):
        raise ValueError(f"disturbance must be a finite number >= 0 rad/s, got {disturbance!r}")
    config = BarrierConfig(safety_distance=safety_radius, gamma=barrier_gain, bounds=bounds)
    params = UnicycleParams(wheel_radius=wheel_radius, axle_length=base_length, max_wheel_speed=wheel_vel_limit,
                            lookahead=projection_distance)
    made: list[UnicycleSafetyFilter] = []  # built on the first call: it knows the robot count then

    def f(dxu, x, obstacles=np.empty(0)):
        dxu = np.asarray(dxu, dtype=float)
        obs = np.asarray(obstacles, dtype=float)
        x = np.asarray(x, dtype=float)
        if not made:
            made.append(UnicycleSafetyFilter(config, params, robots=x.shape[-1] if x.ndim == 2 else None))
        v, w, _ = made[0].filter(x.T, dxu[0], dxu[1],
                             obs.reshape(2, -1).T if obs.size else None)
        return np.vstack((v, w))

    return f


def create_unicycle_differential_drive_barrier_certificate(max_num_obstacle_points: int = 100, max_num_robots: int = 30,
                                                           disturbance: float = 5, wheel_vel_limit: float = MAX_WHEEL_SPEED,
                                                           base_length: float = AXLE_LENGTH, wheel_radius: float = WHEEL_RADIUS,
                                                           projection_distance: float = 0.05, barrier_gain: float = 150,
                                                           safety_radius: float = SAFETY_DISTANCE):
    """f(dxu (2, N), x (3, N), obstacles (2, M) = none) → safe (2, N) [v; ω] within the wheel limits.

    swarmdeck's unicycle barrier: the QP on the look-ahead points (D_s = ``safety_radius``) with each
    robot's four wheel-limit rows |ω_R|, |ω_L| ≤ ``wheel_vel_limit``, obstacles as fixed points.
    rps's preallocation sizes (``max_num_*``) are not limits here. rps tightens each row by the
    worst wheel-speed ``disturbance``; swarmdeck certifies the nominal model instead (the value is
    checked, not used), and ``swarmdeck run`` filters the robots' commands again in any case.
    """
    return _unicycle_dd(barrier_gain, safety_radius, projection_distance, wheel_vel_limit, base_length, wheel_radius,
                        disturbance, _OPEN)


def create_unicycle_differential_drive_barrier_certificate_with_boundary(
        max_num_obstacle_points: int = 100, max_num_robots: int = 30, disturbance: float = 5,
        wheel_vel_limit: float = MAX_WHEEL_SPEED, base_length: float = AXLE_LENGTH, wheel_radius: float = WHEEL_RADIUS,
        projection_distance: float = 0.05, barrier_gain: float = 150, safety_radius: float = SAFETY_DISTANCE,
        boundary_points=np.array(DEFAULT_BOUNDS)):
    """As :func:`create_unicycle_differential_drive_barrier_certificate`, with the arena walls."""
    return _unicycle_dd(barrier_gain, safety_radius, projection_distance, wheel_vel_limit, base_length, wheel_radius,
                        disturbance, _boundary(boundary_points))


def _unsafe_gain(unsafe_barrier_gain: float) -> None:
    if not (np.isfinite(unsafe_barrier_gain) and unsafe_barrier_gain > 0):
        raise ValueError(f"unsafe_barrier_gain must be a finite number > 0, got {unsafe_barrier_gain!r}")


def create_single_integrator_barrier_certificate2(barrier_gain: float = 100, unsafe_barrier_gain: float = 1e6,
                                                  safety_radius: float = SAFETY_DISTANCE, magnitude_limit: float = MAX_LINEAR_SPEED):
    """rps 1.x's variant with a large gain once a pair is inside the unsafe set: f(dxi (2, N), x (2, N)) →
    safe (2, N). swarmdeck's barrier already demands separation there (its recovery rows,
    :class:`~swarmdeck.safety.BarrierConfig`), so ``unsafe_barrier_gain`` is checked, not used."""
    _unsafe_gain(unsafe_barrier_gain)
    return _si(barrier_gain, safety_radius, magnitude_limit, _OPEN)


def create_unicycle_barrier_certificate2(barrier_gain: float = 500, unsafe_barrier_gain: float = 1e6,
                                         safety_radius: float = 0.12, projection_distance: float = 0.05,
                                         magnitude_limit: float = MAX_LINEAR_SPEED):
    """rps 1.x's unicycle variant of :func:`create_single_integrator_barrier_certificate2`."""
    _unsafe_gain(unsafe_barrier_gain)
    return _uni(barrier_gain, safety_radius, projection_distance, magnitude_limit, _OPEN)


# rps 2.0's names (rps/utilities/barrier_certificates.py on `master`), with its defaults
def create_si_barrier_certificate(safety_radius: float = 0.15, barrier_gain: float = 100.0,
                                  magnitude_limit: float = MAX_LINEAR_SPEED):
    """rps 2.0: f(dxi (2, N), x (2, N)) → safe (2, N), pairwise constraints only."""
    return _si(barrier_gain, safety_radius, magnitude_limit, _OPEN)


def create_si_barrier_certificate_with_boundary(safety_radius: float = 0.15, barrier_gain: float = 100.0,
                                                magnitude_limit: float = MAX_LINEAR_SPEED, boundary_points=None):
    """rps 2.0: f(dxi (2, N), x (2, N)) → safe (2, N), with the arena walls (default: the arena's)."""
    return _si(barrier_gain, safety_radius, magnitude_limit,
               _boundary(DEFAULT_BOUNDS if boundary_points is None else boundary_points))


def create_uni_barrier_certificate(barrier_gain: float = 100.0, safety_radius: float = 0.15,
                                   projection_distance: float = 0.05, velocity_magnitude_limit: float = MAX_LINEAR_SPEED):
    """rps 2.0: f(dxu (2, N), x (3, N)) → safe (2, N) [v; ω]."""
    return _uni(barrier_gain, safety_radius, projection_distance, velocity_magnitude_limit, _OPEN)


def create_uni_barrier_certificate_with_boundary(safety_radius: float = 0.12, barrier_gain: float = 150.0,
                                                 projection_distance: float = 0.03,
                                                 velocity_magnitude_limit: float = MAX_LINEAR_SPEED, boundary_points=None):
    """rps 2.0: f(dxu (2, N), x (3, N), obstacles=None) → safe (2, N) [v; ω] within the walls; the
    obstacle segments of rps 2.0 are not supported (refused when given)."""
    inner = _uni(barrier_gain, safety_radius, projection_distance, velocity_magnitude_limit,
                 _boundary(DEFAULT_BOUNDS if boundary_points is None else boundary_points))

    def barrier_unicycle(dxu, x, obstacles=None):
        if obstacles is not None and np.asarray(obstacles).size:
            raise ValueError("obstacles: the rps facade's barrier does not take rps 2.0's obstacle segments")
        return inner(dxu, x)

    return barrier_unicycle


def _solve_qp(N: int, vhat, A, b):
    """rps 2.x: min ‖v − v̂‖² s.t. A v ≤ b for the (2, N) velocities ``vhat`` (stacked column by column, as rps
    does); the (2, N) answer, or None when the QP has no solution (rps returns None then too)."""
    result = project_onto_polytope(np.asarray(vhat, dtype=float).reshape(-1, order="F"), A, b)
    return result.u.reshape((2, int(N)), order="F") if result.ok else None


__all__ = [
    "create_si_barrier_certificate", "create_si_barrier_certificate_with_boundary",
    "create_single_integrator_barrier_certificate", "create_single_integrator_barrier_certificate2",
    "create_single_integrator_barrier_certificate_with_boundary", "create_uni_barrier_certificate",
    "create_uni_barrier_certificate_with_boundary", "create_unicycle_barrier_certificate",
    "create_unicycle_barrier_certificate2", "create_unicycle_barrier_certificate_with_boundary",
    "create_unicycle_differential_drive_barrier_certificate",
    "create_unicycle_differential_drive_barrier_certificate_with_boundary", "np", *_TRANSFORMATIONS,
]
