"""The plain formulation, for benchmarks and cross-checks: every pair, every wall, one clarabel call.

Rows exactly as rps writes them (REFERENCE.md §3): −2eᵀ(u_i − u_j) ≤ γκ(h) for
all N(N−1)/2 pairs, u_x ≤ g·γ·κ(x_max − m − x) (and the other three walls) for
every robot, ‖u_i‖ ≤ v_max as second-order cones; dense Python loops-free
assembly but no pruning and no structure exploited. No recovery rows.
"""
from __future__ import annotations

import numpy as np

from .config import BarrierConfig
from .constraints import PAIR, WALL, Rows
from .qp_clarabel import QPResult, solve_qp


def all_pairs_rows(points: np.ndarray, cfg: BarrierConfig) -> Rows:
    """Unnormalised rps rows for all pairs and all four walls of every robot."""
    n = points.shape[0]
    i, j = np.triu_indices(n, 1)
    e = points[i] - points[j]
    h = np.einsum("kd,kd->k", e, e) - cfg.safety_distance**2
    pair = Rows(i.astype(np.int64), j.astype(np.int64), -2 * e, 2 * e, cfg.gamma * cfg.kappa(h), h,
                np.full(i.size, PAIR, dtype=np.int8), (i * n + j).astype(np.int64))
    x_min, x_max, y_min, y_max = cfg.bounds
    m = cfg.margin
    x, y = points[:, 0], points[:, 1]
    delta = np.stack([x_max - m - x, x - x_min - m, y_max - m - y, y - y_min - m], axis=1).reshape(-1)
    normals = np.tile(np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]]), (n, 1))
    ri = np.repeat(np.arange(n, dtype=np.int64), 4)
    wall = Rows(ri, np.full_like(ri, -1), normals, np.zeros_like(normals),
                cfg.wall_gain * cfg.gamma * cfg.kappa(delta), delta,
                np.full(4 * n, WALL, dtype=np.int8), n * n + np.arange(4 * n, dtype=np.int64))
    return Rows.concat([pair, wall])


def all_pairs_filter(points: np.ndarray, nominal: np.ndarray, cfg: BarrierConfig | None = None) -> QPResult:
    """Solve the unpruned barrier QP (the in-process baseline of ``bench/bench_safety.py``)."""
    cfg = BarrierConfig() if cfg is None else cfg
    rows = all_pairs_rows(points, cfg)
    return solve_qp(rows, nominal, cfg.max_speed, max_iter=cfg.clarabel_max_iter, tol=cfg.clarabel_tol)
