"""Routes around line-segment obstacles for the fleet's maneuvers (setup and return).

A maneuver is a barrier-filtered go-to-goal; a segment straight between a robot and its goal would hold
it against the segment (the barrier removes the approach, nothing is left to go round). :class:`Router`
gives each robot a waypoint instead: its goal when the straight path keeps ``clearance`` m from every
segment, else the next corner of the shortest path over a visibility graph whose nodes sit just beyond
the segments' ends (``node_factor · clearance`` m out, diagonally). The node graph and its all-pairs
shortest paths are built once per obstacle set (:meth:`Router.for_goals` adds the goals once per
maneuver phase); each tick costs one visibility test per blocked robot and node (vectorised).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.bounds import Bounds
from swarmdeck.core.obstacles import START_CLEARANCE, Obstacles, point_segment_distance
from swarmdeck.devices.chargers import ChargerLayout

FloatArray = NDArray[np.float64]

_REACHED = 0.05  # m: a node this close to the robot is behind it: aim at the next one


def check_chargers_clear(obstacles: Obstacles | None, layout: ChargerLayout) -> None:
    """ObstacleError naming the first segment of ``obstacles`` within :data:`START_CLEARANCE` of a charger slot
    or of its approach pose (where a returning robot turns before it reverses onto the slot: a segment that
    near leaves it no room to turn, and the return could never finish)."""
    if obstacles is None:
        return
    obstacles.check_clear(layout.dock_poses()[:, :2], START_CLEARANCE, "charger slot")
    obstacles.check_clear(layout.approach_poses()[:, :2], START_CLEARANCE, "the approach pose of charger slot")


def clear_paths(a: FloatArray, b: FloatArray, segments: FloatArray, clearance: float,
                from_robot: bool = False, to_goal: bool = False) -> NDArray[np.bool_]:
    """``(K,)`` whether each straight path ``a[k] → b[k]`` (``(K, 2)`` m) keeps ``clearance`` m from every
    segment ``(S, 2, 2)``: no crossing, and every end of either at least ``clearance`` from the other.
    ``from_robot``: ``a`` is where a robot is (it may be nearer a segment than ``clearance``: the barrier
    lets it); ``to_goal``: ``b`` is a goal (a charger's approach pose may be that near too). Their own
    distance is not asked then, only that the path does not cross or pass a segment's end."""
    k = a.shape[0]
    if k == 0 or segments.shape[0] == 0:
        return np.ones(k, dtype=bool)
    p, q = a[:, None, :], b[:, None, :]
    c, d = segments[None, :, 0], segments[None, :, 1]

    def orient(u: FloatArray, v: FloatArray, w: FloatArray) -> FloatArray:
        return (v[..., 0] - u[..., 0]) * (w[..., 1] - u[..., 1]) - (v[..., 1] - u[..., 1]) * (w[..., 0] - u[..., 0])

    crossing = (orient(p, q, c) * orient(p, q, d) <= 0) & (orient(c, d, p) * orient(c, d, q) <= 0)

    def dist(x: FloatArray, s0: FloatArray, s1: FloatArray) -> FloatArray:  # point (.., 2) to segment s0–s1
        ab = s1 - s0
        t = np.clip(np.sum((x - s0) * ab, axis=-1) / np.maximum(np.sum(ab * ab, axis=-1), 1e-300), 0.0, 1.0)
        return np.linalg.norm(x - (s0 + t[..., None] * ab), axis=-1)

    near = np.minimum(dist(c, p, q), dist(d, p, q))
    if not from_robot:
        near = np.minimum(near, dist(p, c, d))
    if not to_goal:
        near = np.minimum(near, dist(q, c, d))
    return ~np.any(crossing | (near < clearance), axis=1)


@dataclass
class Router:
    """Waypoints round ``obstacles`` (module docstring) inside ``bounds``.

    clearance: m a path keeps from every segment (default: the start poses' clearance, D_s/2 + ℓ).
    node_factor: the nodes' distance beyond a segment's end, × clearance.
    """

    obstacles: Obstacles
    bounds: Bounds
    clearance: float = START_CLEARANCE
    node_factor: float = 1.6
    nodes: FloatArray = field(init=False)
    _between: FloatArray = field(init=False)  # (P, P) shortest path lengths between nodes, m (inf: none)

    def __post_init__(self) -> None:
        seg = self.obstacles.segments
        r = self.node_factor * self.clearance
        ends = np.concatenate([seg[:, 1], seg[:, 0]])  # (2S, 2)
        out = np.concatenate([seg[:, 1] - seg[:, 0], seg[:, 0] - seg[:, 1]])
        out /= np.linalg.norm(out, axis=1, keepdims=True)
        normal = np.column_stack([-out[:, 1], out[:, 0]])
        diag = np.sqrt(0.5)
        cand = np.concatenate([ends + r * diag * (out + normal), ends + r * diag * (out - normal),
                               ends + r * normal, ends - r * normal])
        b = Bounds.of(self.bounds)
        keep = b.contains(cand, margin=self.clearance)
        if seg.shape[0] and cand.shape[0]:
            keep &= point_segment_distance(cand, seg).min(axis=1) >= self.clearance
        self.nodes = cand[keep]
        p = self.nodes.shape[0]
        i, j = np.triu_indices(p, 1)
        visible = clear_paths(self.nodes[i], self.nodes[j], seg, self.clearance)
        graph = np.zeros((p, p))
        length = np.linalg.norm(self.nodes[i] - self.nodes[j], axis=1)
        graph[i[visible], j[visible]] = length[visible]
        graph = graph + graph.T
        from scipy.sparse.csgraph import shortest_path  # lazy: see test_devices_rps_startup_imports

        self._between = shortest_path(graph, method="D", directed=False) if p else np.zeros((0, 0))

    def for_goals(self, goals: FloatArray) -> RoutePlan:
        """The routes to the goals ``(K, 2)`` m of one maneuver (the path length from every node to each)."""
        g = np.asarray(goals, dtype=float)[:, :2].copy()
        k, p = g.shape[0], self.nodes.shape[0]
        if p == 0 or k == 0:
            return RoutePlan(self, g, np.full((k, p), np.inf))
        gi, ni = np.repeat(np.arange(k), p), np.tile(np.arange(p), k)
        vis = clear_paths(g[gi], self.nodes[ni], self.obstacles.segments, self.clearance,
                          from_robot=True).reshape(k, p)  # the goal's own clearance is not asked
        direct = np.where(vis, np.linalg.norm(g[:, None] - self.nodes[None], axis=2), np.inf)  # (K, P)
        # to goal k from node n: the best node m that sees the goal, then the graph from n to m
        return RoutePlan(self, g, np.min(direct[:, None, :] + self._between[None, :, :], axis=2))


@dataclass(frozen=True)
class RoutePlan:
    """The routes of one maneuver: ``goals`` ``(K, 2)`` m and ``to_goal`` ``(K, P)`` the path length from each
    node of ``router`` to each goal, m (inf: none)."""

    router: Router
    goals: FloatArray
    to_goal: FloatArray

    def waypoints(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        """``(waypoints (K, 2), route length (K,))`` m for robots at ``points`` ``(K, 2)`` heading for the goals.
        A robot that sees its goal (or for which no route is known) aims at it directly."""
        pts = np.asarray(points, dtype=float)[:, :2]
        rt = self.router
        goal = self.goals
        wp, length = goal.copy(), np.linalg.norm(goal - pts, axis=1)
        seg = rt.obstacles.segments
        blocked = np.flatnonzero(~clear_paths(pts, goal, seg, rt.clearance, from_robot=True, to_goal=True))
        p = rt.nodes.shape[0]
        if blocked.size == 0 or p == 0:
            return wp, length
        bi, ni = np.repeat(blocked, p), np.tile(np.arange(p), blocked.size)
        vis = clear_paths(pts[bi], rt.nodes[ni], seg, rt.clearance, from_robot=True).reshape(blocked.size, p)
        to_node = np.linalg.norm(pts[blocked, None] - rt.nodes[None], axis=2)
        cost = np.where(vis & (to_node > _REACHED), to_node + self.to_goal[blocked], np.inf)
        best = np.argmin(cost, axis=1)
        found = np.isfinite(cost[np.arange(blocked.size), best])
        wp[blocked[found]] = rt.nodes[best[found]]
        length[blocked[found]] = cost[np.arange(blocked.size), best][found]
        return wp, length
