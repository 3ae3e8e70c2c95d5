"""rps 1.x's ``rps.utilities.barrier_certificates2``: ``create_robust_barriers`` on swarmdeck's unicycle barrier."""
from __future__ import annotations

import numpy as np

from swarmdeck.devices.rps.utilities.barrier_certificates import create_unicycle_differential_drive_barrier_certificate


def create_robust_barriers(max_num_obstacles: int = 100, max_num_robots: int = 30, d: float = 5,
                           wheel_vel_limit: float = 12.5, base_length: float = 0.105, wheel_radius: float = 0.016,
                           projection_distance: float = 0.05, gamma: float = 150, safety_radius: float = 0.12):
    """f(dxu (2, N), x (3, N), obstacles (2, M)) → safe (2, N) [v; ω]: rps's robust differential-drive
    barrier, here :func:`~swarmdeck.devices.rps.utilities.barrier_certificates.create_unicycle_differential_drive_barrier_certificate`
    (the wheel-speed disturbance ``d`` is checked, not used; see there)."""
    inner = create_unicycle_differential_drive_barrier_certificate(
        max_num_obstacle_points=max_num_obstacles, max_num_robots=max_num_robots, disturbance=d,
        wheel_vel_limit=wheel_vel_limit, base_length=base_length, wheel_radius=wheel_radius,
        projection_distance=projection_distance, barrier_gain=gamma, safety_radius=safety_radius)

    def robust_barriers(dxu, x, obstacles=np.empty(0)):
        return inner(dxu, x, obstacles)

    return robust_barriers


__all__ = ["create_robust_barriers", "np"]
