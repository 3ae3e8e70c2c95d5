"""Per-robot observations (vectorised over robots).

Row i of :func:`observe` (float32), with ``k`` = number of neighbours observed:

=========================  =====  ============================================================
part                       size   content (m, rad; arena frame)
=========================  =====  ============================================================
own pose                   4      x_i, y_i, cos θ_i, sin θ_i
neighbours                 2k     p_j − p_i of the k nearest robots, nearest first (look-ahead
                                  points); zeros beyond N − 1 robots
walls                      4      x_i − x_min, x_max − x_i, y_i − y_min, y_max − y_i
task                       0 / 2  formation: g_i − p_i (own slot); others: nothing
density (optional)         9      φ at p_i + (dx, dy), dx, dy ∈ {−s, 0, s}, divided by max φ
ToF sensors (optional)     K      the robot's own distance readings divided by their range, in [0, 1];
                                  1 where nothing is in range or the reading dropped out (:func:`tof_block`)
=========================  =====  ============================================================
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.bounds import Bounds
from swarmdeck.envs.neighbours import nearest_neighbours

FloatArray = NDArray[np.float64]

DENSITY_OFFSETS = np.array([(dx, dy) for dy in (-1.0, 0.0, 1.0) for dx in (-1.0, 0.0, 1.0)])


def observation_size(k: int, task: str, density: bool, sensors: int = 0) -> int:
    """Length of one robot's observation (``sensors``: K ToF readings at the end, 0: none)."""
    return 4 + 2 * k + 4 + (2 if task == "formation" else 0) + (9 if density else 0) + sensors


def tof_block(distances: FloatArray, max_range: float) -> NDArray[np.float32]:
    """The ToF block ``(N, K)`` of the observations: readings (m; −1 nothing, NaN not read yet) / ``max_range``,
    with nothing in range, dropouts and not-yet-read as 1 (as far as the sensor sees)."""
    d = np.asarray(distances, dtype=float)
    with np.errstate(invalid="ignore"):
        seen = d >= 0.0
    return np.where(seen, np.clip(d / max_range, 0.0, 1.0), 1.0).astype(np.float32)


def observe(poses: FloatArray, points: FloatArray, bounds: tuple[float, float, float, float], k: int,
            slots: FloatArray | None = None, density: Any = None, density_step: float = 0.15,
            density_scale: float = 1.0) -> NDArray[np.float32]:
    """(N, D) observations (table in the module docstring); ``k`` neighbours (padded with zeros when N − 1 < k)."""
    n = len(poses)
    x0, x1, y0, y1 = bounds
    parts = [poses[:, :2], np.cos(poses[:, 2:3]), np.sin(poses[:, 2:3])]
    rel = np.zeros((n, k, 2))
    kk = min(k, n - 1)
    if kk > 0:
        idx = nearest_neighbours(points, kk)
        rel[:, :kk] = points[idx] - points[:, None, :]
    parts.append(rel.reshape(n, 2 * k))
    parts.append(np.column_stack((points[:, 0] - x0, x1 - points[:, 0], points[:, 1] - y0, y1 - points[:, 1])))
    if slots is not None:
        parts.append(slots - points)
    if density is not None:
        q = points[:, None, :] + density_step * DENSITY_OFFSETS[None, :, :]
        parts.append(np.asarray(density.evaluate(q), dtype=float) / density_scale)
    return np.concatenate(parts, axis=1).astype(np.float32)


def observation_bounds(k: int, task: str, density: bool, bounds: tuple[float, float, float, float],
                       sensors: int = 0) -> tuple[NDArray[np.float32], NDArray[np.float32]]:
    """(low, high) of one observation: positions within the arena, differences within its diagonal."""
    b = Bounds.of(bounds)
    x0, x1, y0, y1 = b
    span = float(np.hypot(b.width, b.height))
    m = max(abs(x0), abs(x1), abs(y0), abs(y1))
    lo = [-m, -m, -1.0, -1.0] + [-span] * (2 * k) + [-span] * 4
    hi = [m, m, 1.0, 1.0] + [span] * (2 * k) + [span] * 4
    if task == "formation":
        lo += [-2 * span] * 2
        hi += [2 * span] * 2
    if density:
        lo += [0.0] * 9
        hi += [1.0] * 9
    lo += [0.0] * sensors
    hi += [1.0] * sensors
    return np.asarray(lo, dtype=np.float32), np.asarray(hi, dtype=np.float32)
