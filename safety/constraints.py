"""Barrier rows that can bind, built with a k-d tree and no per-robot loops.

Every row acts on at most two robots and is stored as a structure of arrays
(:class:`Rows`): ``ci·u_i + cj·u_j ≤ b`` with ``cj = 0`` for single-robot rows.
Rows are normalised so the coefficient vectors are unit vectors and ``b`` is a
speed in m/s; this leaves the feasible set, and so the QP's solution, unchanged.

* pair (REFERENCE.md §3): −2(x_i − x_j)ᵀ(u_i − u_j) ≤ γκ(h_ij), h_ij = ‖x_i − x_j‖² − D_s²,
  stored as ``n_ijᵀ(u_j − u_i) ≤ γκ(h_ij)/(2‖x_i − x_j‖)`` with n_ij the unit vector from j to i;
* obstacle (fixed point o): −2(x_i − o)ᵀu_i ≤ γκ(h_io), the robot alone keeps the distance;
* wall (rps): u_x ≤ g·γ·κ(x_max − m − x) and the three analogous rows, g = wall_gain,
  m = wall margin; here h is the clearance δ beyond the margin (m).
* segment (a line-segment obstacle of ``cfg.obstacles``, :mod:`swarmdeck.core.obstacles`):
  −n_ikᵀu_i ≤ g·γ·κ(h_ik), h_ik = ‖x_i − q_ik‖ − m with q_ik the nearest point of segment k and
  n_ik the unit vector from q_ik to x_i (m, g as for the walls; the robot alone keeps it). The
  distance to a segment is convex, so d(x + u·dt) ≥ d(x) + n_ᵀu·dt and the discrete closed loop
  keeps h ≥ 0 under the same condition as the walls.

Rows farther than the binding distance (``BarrierConfig.neighbour_radius`` /
``wall_radius``) cannot be active for any command with ‖u_i‖ ≤ v_max and are
not built.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from swarmdeck.core.graphs import DENSE_PAIRS_ROBOTS, pairs_within
from swarmdeck.core.obstacles import nearest_points, segments_near

if TYPE_CHECKING:
    from scipy.spatial import cKDTree

from .config import BarrierConfig

PAIR, WALL, OBSTACLE, LIMIT, SEGMENT = 0, 1, 2, 3, 4
_WALL_NORMALS = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]])  # sides +x, −x, +y, −y
_WALL_NORMALS.flags.writeable = False
_GOLDEN = 2.399963229728653  # golden angle, rad: deterministic directions for coincident points


@dataclass(frozen=True)
class Rows:
    """Linear constraints ``ci·u_i + cj·u_j ≤ b`` (m rows), one or two robots each.

    i, j: (m,) int robot indices (j = −1 for single-robot rows); ci, cj: (m, 2);
    b: (m,) m/s; h: (m,) barrier value (pair/obstacle: m², wall/segment: m, limit: +inf);
    kind: (m,) PAIR/WALL/OBSTACLE/LIMIT/SEGMENT; key: (m,) int64 identity across ticks
    (pair i<j: i·N + j; wall: N² + 4i + side; obstacle: N² + 4N + i·M + k;
    limit rows: N² + 4N + N·M + 4i + s; segment: N² + 8N + N·M + i·S + k, S segments).
    """

    i: np.ndarray
    j: np.ndarray
    ci: np.ndarray
    cj: np.ndarray
    b: np.ndarray
    h: np.ndarray
    kind: np.ndarray
    key: np.ndarray

    @property
    def m(self) -> int:
        return int(self.b.shape[0])

    @cached_property
    def jj(self) -> np.ndarray:
        """Second robot index with single-robot rows pointing at their own robot (cj = 0 there); computed once per
        Rows (its arrays are never modified: every change makes a new Rows)."""
        return np.where(self.j < 0, self.i, self.j)

    def lhs(self, u: np.ndarray) -> np.ndarray:
        """Left-hand sides ``ci·u_i + cj·u_j`` for velocities u (N, 2) → (m,)."""
        jj = self.jj
        return np.einsum("kd,kd->k", self.ci, u[self.i]) + np.einsum("kd,kd->k", self.cj, u[jj])

    def select(self, mask: np.ndarray) -> Rows:
        """The rows where ``mask`` is true (boolean or index array)."""
        return Rows(*(getattr(self, f)[mask] for f in _FIELDS))

    @staticmethod
    def concat(parts: list[Rows]) -> Rows:
        """The rows of ``parts`` in order (one part holding rows alone: that part itself, whose arrays are the
        concatenation's values and dtypes: every builder makes int64 indices, int8 kinds and float rows)."""
        full = [p for p in parts if p.b.shape[0]]
        if len(full) == 1 and all(map(_canonical, parts)):
            return full[0]
        return Rows(*(np.concatenate([getattr(p, f) for p in parts]) for f in _FIELDS))

    @staticmethod
    def empty() -> Rows:
        z = np.zeros(0)
        zi = np.zeros(0, dtype=np.int64)
        z2 = np.zeros((0, 2))
        return Rows(zi, zi, z2, z2, z, z, np.zeros(0, dtype=np.int8), zi)


_FIELDS = ("i", "j", "ci", "cj", "b", "h", "kind", "key")
_INT64, _FLOAT, _INT8 = np.dtype(np.int64), np.dtype(float), np.dtype(np.int8)


def _canonical(p: Rows) -> bool:
    """Whether ``p``'s arrays have the dtypes every row builder makes (int64 indices and keys, float rows, int8
    kinds): then concatenating it with others of the same kind changes no dtype."""
    return (p.i.dtype == _INT64 and p.j.dtype == _INT64 and p.key.dtype == _INT64 and p.kind.dtype == _INT8
            and p.ci.dtype == _FLOAT and p.cj.dtype == _FLOAT and p.b.dtype == _FLOAT and p.h.dtype == _FLOAT)


def _unit_or_fallback(e: np.ndarray, d: np.ndarray, seed: np.ndarray) -> np.ndarray:
    """Unit vectors e/d; for coincident points (d ≈ 0) a deterministic direction from ``seed``."""
    tiny = d < 1e-12
    n = e / np.where(tiny, 1.0, d)[:, None]
    if tiny.any():
        phi = _GOLDEN * seed[tiny].astype(float)
        n[tiny] = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    return n


def pair_rows(points: np.ndarray, cfg: BarrierConfig, tree: cKDTree | None = None) -> Rows:
    """Pair rows for all pairs closer than ``cfg.neighbour_radius()`` (``tree``'s query, or
    :func:`~swarmdeck.core.graphs.pairs_within`: all pairs compared for a few robots, a k-d tree above)."""
    n_robots = points.shape[0]
    if n_robots < 2:
        return Rows.empty()
    if tree is None:
        pairs = pairs_within(points, cfg.neighbour_radius())
    else:
        pairs = tree.query_pairs(cfg.neighbour_radius(), output_type="ndarray")
    if pairs.shape[0] == 0:
        return Rows.empty()
    if tree is None:  # pairs_within's pairs are in key order already (i, then j; i < j < N)
        i = pairs[:, 0].astype(np.int64)
        j = pairs[:, 1].astype(np.int64)
        key = i * n_robots + j
    else:
        # rows in key order (i, then j; query_pairs gives i < j): one sort of int64 keys
        key = np.sort(pairs[:, 0].astype(np.int64) * n_robots + pairs[:, 1])
        i, j = np.divmod(key, n_robots)
    e = points[i] - points[j]
    d = np.sqrt(np.einsum("kd,kd->k", e, e))
    n = _unit_or_fallback(e, d, key)
    h = d * d - cfg.safety_distance**2
    b = cfg.gamma * cfg.kappa(h) / (2.0 * np.maximum(d, 1e-12))
    kind = np.full(i.shape[0], PAIR, dtype=np.int8)
    return Rows(i, j, -n, n, b, h, kind, key)


def obstacle_rows(points: np.ndarray, obstacles: np.ndarray, cfg: BarrierConfig,
                  tree: cKDTree | None = None) -> Rows:
    """Rows keeping each robot D_s from fixed obstacle points (M, 2) within the neighbour radius."""
    n_robots, n_obs = points.shape[0], obstacles.shape[0]
    if n_robots == 0 or n_obs == 0:
        return Rows.empty()
    from scipy.spatial import cKDTree  # lazy: see test_devices_rps_startup_imports

    tree = cKDTree(points) if tree is None else tree
    close = tree.sparse_distance_matrix(cKDTree(obstacles), cfg.neighbour_radius(),
                                        output_type="ndarray")
    # sparse_distance_matrix drops exact zero distances; coincident points are found separately.
    i = close["i"].astype(np.int64)
    k = close["j"].astype(np.int64)
    zi, zk = _coincident(points, obstacles, tree)
    if zi.size:
        i, k = np.concatenate([i, zi]), np.concatenate([k, zk])
        i, k = np.unique(np.stack([i, k], axis=1), axis=0).T
    if i.size == 0:
        return Rows.empty()
    order = np.lexsort((k, i))
    i, k = i[order], k[order]
    e = points[i] - obstacles[k]
    d = np.sqrt(np.einsum("kd,kd->k", e, e))
    key = n_robots * n_robots + 4 * n_robots + i * n_obs + k
    n = _unit_or_fallback(e, d, key)
    h = d * d - cfg.safety_distance**2
    b = cfg.gamma * cfg.kappa(h) / (2.0 * np.maximum(d, 1e-12))
    kind = np.full(i.shape[0], OBSTACLE, dtype=np.int8)
    return Rows(i, np.full_like(i, -1), -n, np.zeros_like(n), b, h, kind, key)


def _coincident(points: np.ndarray, obstacles: np.ndarray, tree: cKDTree) -> tuple[np.ndarray, np.ndarray]:
    dist, idx = tree.query(obstacles, k=1)
    hit = np.flatnonzero(dist == 0.0)
    return idx[hit].astype(np.int64), hit.astype(np.int64)


def wall_rows(points: np.ndarray, cfg: BarrierConfig, bounds: np.ndarray | None = None) -> Rows:
    """Wall rows for robots within ``cfg.wall_radius()`` of a wall (sides +x, −x, +y, −y).

    ``bounds``: None (every robot inside ``cfg.bounds``) or ``(N, 4)`` per-robot rectangles
    ``[x_min, x_max, y_min, y_max]`` in m — the region each robot must stay in when several
    experiments share one floor (:mod:`swarmdeck.devices.fleet.regions`); the margin and gain are
    ``cfg``'s for every robot. Vectorised: one comparison per robot and side.
    """
    n_robots = points.shape[0]
    x_min: float | np.ndarray
    x_max: float | np.ndarray
    y_min: float | np.ndarray
    y_max: float | np.ndarray
    if bounds is None:  # one rectangle: scalars (the same IEEE operations as per-robot arrays of them)
        x_min, x_max, y_min, y_max = (float(v) for v in cfg.bounds)
    else:
        per = np.asarray(bounds, dtype=float)
        if per.shape != (n_robots, 4):
            raise ValueError(f"per-robot bounds must have shape ({n_robots}, 4), got {per.shape}")
        x_min, x_max, y_min, y_max = per.T
    m = cfg.margin
    x, y = points[:, 0], points[:, 1]
    clearance = np.stack([x_max - m - x, x - x_min - m, y_max - m - y, y - y_min - m], axis=1)  # (N,4)
    near = clearance <= cfg.wall_radius() - m
    if not near.any():
        return Rows.empty()  # the same empty arrays (dtypes and shapes) as below
    i, side = np.nonzero(near)
    i = i.astype(np.int64)
    side = side.astype(np.int64)
    delta = clearance[i, side]
    b = cfg.wall_gain * cfg.gamma * cfg.kappa(delta)
    kind = np.full(i.shape[0], WALL, dtype=np.int8)
    key = n_robots * n_robots + 4 * i + side
    ci = _WALL_NORMALS[side]
    return Rows(i, np.full_like(i, -1), ci, np.zeros_like(ci), b, delta, kind, key)


def segment_rows(points: np.ndarray, cfg: BarrierConfig, n_obs: int = 0) -> Rows:
    """Rows keeping each controlled point (N, 2) the wall margin from every segment of ``cfg.obstacles``
    within ``cfg.wall_radius()`` (m) — found by :func:`~swarmdeck.core.obstacles.segments_near`, no N×S
    array. ``n_obs``: the number of fixed points (M) this call's keys must stay clear of."""
    obs = cfg.obstacles
    n_robots = points.shape[0]
    if obs is None or obs.m == 0 or n_robots == 0:
        return Rows.empty()
    seg = obs.segments
    i, k, d = segments_near(points, seg, cfg.wall_radius())
    if i.size == 0:
        return Rows.empty()
    e = points[i] - nearest_points(points[i], seg[k])
    tiny = d < 1e-12
    n = e / np.where(tiny, 1.0, d)[:, None]
    if tiny.any():  # on the segment: its left normal (deterministic)
        t = seg[k[tiny], 1] - seg[k[tiny], 0]
        n[tiny] = np.stack([-t[:, 1], t[:, 0]], axis=1) / np.linalg.norm(t, axis=1)[:, None]
    h = d - cfg.margin
    b = cfg.wall_gain * cfg.gamma * cfg.kappa(h)
    key = n_robots * n_robots + 8 * n_robots + n_robots * n_obs + i * obs.m + k
    kind = np.full(i.shape[0], SEGMENT, dtype=np.int8)
    return Rows(i, np.full_like(i, -1), -n, np.zeros_like(n), b, h, kind, key)


def barrier_rows(points: np.ndarray, cfg: BarrierConfig, obstacles: np.ndarray | None = None,
                 tree: cKDTree | None = None, robot_bounds: np.ndarray | None = None) -> Rows:
    """All candidate rows (pairs unless ``cfg.pairs`` is False, walls, obstacles, segments of
    ``cfg.obstacles``) for controlled points (N, 2);
    ``robot_bounds`` ``(N, 4)``: each robot's own wall rectangle (:func:`wall_rows`), None: ``cfg.bounds``."""
    if points.shape[0] == 0:
        return Rows.empty()
    with_obstacles = obstacles is not None and obstacles.shape[0] > 0
    if tree is None and (points.shape[0] > DENSE_PAIRS_ROBOTS or with_obstacles):  # one tree for both queries
        from scipy.spatial import cKDTree  # lazy: see test_devices_rps_startup_imports

        tree = cKDTree(points)
    parts = ([pair_rows(points, cfg, tree)] if cfg.pairs else []) + [wall_rows(points, cfg, robot_bounds)]
    if obstacles is not None and with_obstacles:
        parts.append(obstacle_rows(points, obstacles, cfg, tree))
    if cfg.obstacles is not None and cfg.obstacles.m:
        parts.append(segment_rows(points, cfg, 0 if obstacles is None else obstacles.shape[0]))
    return Rows.concat(parts)
