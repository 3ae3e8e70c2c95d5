"""Charging strips along the arena walls and the docking slots on them (paper §III-C "Charging").

A GRITSBot charges by backing onto a magnetic strip in the wall: two prongs at its back touch the
strip. A slot is one docking place on a strip: the docked robot's centre sits ``dock_depth`` m
from the wall, its heading is the wall's inward normal (its back faces the wall), so it leaves
the dock by driving straight forward and docks by reversing straight back from its *approach
pose* ``approach_distance`` m further in.

Slots are spaced ``slot_spacing`` m along each wall with strips, centred on the wall and at least
``corner_clearance`` m from the corners, so a larger arena gets more slots. The defaults fit the
3.2 m × 2 m arena (REFERENCE.md §1) and its robots: 16 slots on each long wall and 9 on each
short one, 50 in all; 0.18 m between slots keeps the look-ahead points of neighbouring docked
robots (ℓ = 0.03 m, same heading) farther apart than the barrier's D_s = 0.17 m.

Walls are numbered 0 bottom (y = y_min), 1 top, 2 left (x = x_min), 3 right.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds, check_bounds
from swarmdeck.core.checks import require_positive

FloatArray = NDArray[np.float64]
WALLS = ("bottom", "top", "left", "right")
#: inward normal heading of each wall, rad (a docked robot faces into the arena)
_INWARD = np.array([np.pi / 2, -np.pi / 2, 0.0, np.pi])


@dataclass(frozen=True)
class ChargerLayout:
    """Where the charging strips are and how robots dock on them.

    Attributes:
        bounds: the arena ``(x_min, x_max, y_min, y_max)``, m.
        walls: which walls carry strips (names from ``WALLS``).
        slot_spacing: distance between neighbouring slot centres along a wall, m.
        dock_depth: distance from the wall to a docked robot's centre, m (≥ the robot radius
            0.055 m: the body touches the strip; the default leaves 5 mm for the prongs).
        approach_distance: distance from the dock, straight into the arena, of the pose a
            robot reverses from when it docks (and reaches first when it undocks), m.
        approach_stagger: every second slot along a wall has its approach pose this much further
            in, m, so robots lining up in front of neighbouring slots (0.18 m apart) have room to turn.
        corner_clearance: no slot centre closer than this to a corner along its wall, m.
    """

    bounds: Bounds = DEFAULT_BOUNDS
    walls: tuple[str, ...] = WALLS
    slot_spacing: float = 0.18
    dock_depth: float = 0.06
    approach_distance: float = 0.2
    approach_stagger: float = 0.2
    corner_clearance: float = 0.25

    def __post_init__(self) -> None:
        object.__setattr__(self, "bounds", check_bounds(self.bounds, "ChargerLayout.bounds"))
        object.__setattr__(self, "walls", tuple(self.walls))
        require_positive(self, ("slot_spacing", "dock_depth", "approach_distance"), "m")
        require_positive(self, ("corner_clearance", "approach_stagger"), "m", allow_zero=True)
        unknown = [w for w in self.walls if w not in WALLS]
        if unknown or len(set(self.walls)) != len(self.walls):
            raise ValueError(f"ChargerLayout.walls must be distinct names from {WALLS}, got {self.walls!r}")
        x0, x1, y0, y1 = self.bounds
        reach = self.dock_depth + self.approach_distance + self.approach_stagger
        if reach >= min(x1 - x0, y1 - y0) / 2:
            raise ValueError(f"ChargerLayout: dock_depth + approach_distance + approach_stagger ({reach:g} m) "
                             f"reaches past the middle of the {x1 - x0:g} m x {y1 - y0:g} m arena")

    @cached_property
    def _table(self) -> tuple[FloatArray, NDArray[np.intp], NDArray[np.intp]]:
        x0, x1, y0, y1 = self.bounds
        d, s, c = self.dock_depth, self.slot_spacing, self.corner_clearance
        poses, walls, rank = [], [], []
        for name in self.walls:  # at most 4 walls, once per layout
            k = WALLS.index(name)
            lo, hi = (x0, x1) if k < 2 else (y0, y1)
            usable = hi - lo - 2 * c
            if usable < 0:
                continue
            count = int(np.floor(usable / s + 1e-9)) + 1
            along = (lo + hi) / 2 + (np.arange(count) - (count - 1) / 2) * s
            fixed = (y0 + d, y1 - d, x0 + d, x1 - d)[k]
            xy = np.column_stack((along, np.full(count, fixed))) if k < 2 else np.column_stack((np.full(count, fixed), along))
            poses.append(np.column_stack((xy, np.full(count, _INWARD[k]))))
            walls.append(np.full(count, k, dtype=np.intp))
            rank.append(np.arange(count))
        if not poses:
            return np.empty((0, 3)), np.empty(0, dtype=np.intp), np.empty(0, dtype=np.intp)
        return np.vstack(poses), np.concatenate(walls), np.concatenate(rank)

    @property
    def n_slots(self) -> int:
        """Number of slots M."""
        return int(len(self._table[0]))

    def dock_poses(self) -> FloatArray:
        """``(M, 3)`` docked poses ``[x, y, θ]`` (m, rad), slot by slot (a copy)."""
        return self._table[0].copy()

    def slot_walls(self) -> NDArray[np.intp]:
        """``(M,)`` wall index of each slot (0 bottom, 1 top, 2 left, 3 right)."""
        return self._table[1].copy()

    def approach_poses(self) -> FloatArray:
        """``(M, 3)`` poses straight in from each dock, same heading: ``approach_distance`` m, plus
        ``approach_stagger`` m for every second slot along a wall."""
        p = self.dock_poses()
        dist = self.approach_distance + self.approach_stagger * (self._table[2] % 2)
        p[:, 0] += dist * np.cos(p[:, 2])
        p[:, 1] += dist * np.sin(p[:, 2])
        return p

    def docked_slot(self, poses: NDArray[np.float64], position_tolerance: float = 0.02,
                    heading_tolerance: float = 0.35) -> NDArray[np.intp]:
        """``(N,)`` the slot each robot of ``poses`` ``(N, 3)`` is docked on, −1 for none: its centre
        within ``position_tolerance`` m of the slot's dock pose and its heading within
        ``heading_tolerance`` rad of the slot's (its back on the strip, the prongs touching)."""
        p = np.asarray(poses, dtype=float).reshape(-1, 3)
        docks = self._table[0]
        out = np.full(len(p), -1, dtype=np.intp)
        if not len(docks) or not len(p):
            return out
        from scipy.spatial import cKDTree

        finite = np.all(np.isfinite(p), axis=1)
        d, k = cKDTree(docks[:, :2]).query(np.where(finite[:, None], p[:, :2], 1e9))
        k = np.minimum(k, len(docks) - 1)
        heading = np.abs(np.angle(np.exp(1j * (p[:, 2] - docks[k, 2]))))
        ok = finite & (d <= position_tolerance) & (np.where(finite, heading, np.inf) <= heading_tolerance)
        out[ok] = k[ok]
        return out

    def dock_blocks(self, lookahead: float = 0.03, safety_distance: float = 0.17) -> NDArray[np.bool_]:
        """``(M, M)``: ``[a, b]`` is True when a robot docked on slot a blocks slot b — its look-ahead
        point lies within ``safety_distance`` (+ 5 mm) of the path of b's look-ahead point from b's
        approach pose to its dock (near a corner). Slot b must then be filled before slot a.
        Neighbours on one wall dock in parallel lanes and never block each other."""
        d0, a0 = self.dock_poses(), self.approach_poses()
        head = np.column_stack((np.cos(d0[:, 2]), np.sin(d0[:, 2])))
        dock_pt, app_pt = d0[:, :2] + lookahead * head, a0[:, :2] + lookahead * head
        seg = app_pt - dock_pt  # (M, 2) lane of each slot's point
        rel = dock_pt[:, None, :] - dock_pt[None, :, :]  # [a, b]: a's docked point relative to b's lane start
        t = np.clip(np.einsum("abd,bd->ab", rel, seg) / np.einsum("bd,bd->b", seg, seg)[None, :], 0.0, 1.0)
        near = rel - t[..., None] * seg[None, :, :]
        out = np.hypot(near[..., 0], near[..., 1]) < safety_distance + 0.005
        walls = self.slot_walls()
        return out & (walls[:, None] != walls[None, :])

    def approaches_clash(self, clearance: float = 0.25) -> NDArray[np.bool_]:
        """``(M, M)`` symmetric: slots on different walls (at a corner) whose approach poses are closer
        than ``clearance`` m — two robots cannot wait there at once, so they dock one after the other."""
        a = self.approach_poses()[:, :2]
        d = np.hypot(*(a[:, None, :] - a[None, :, :]).transpose(2, 0, 1))
        walls = self.slot_walls()
        return (d < clearance) & (walls[:, None] != walls[None, :])

    def check_reachable(self, bounds: Bounds, safety_distance: float, lookahead: float, radius: float) -> None:
        """Raise ValueError naming the first unreachable slot for robots of body ``radius`` m whose
        look-ahead points (``lookahead`` m ahead) must stay ``safety_distance`` m apart in arena ``bounds``.

        A slot is unreachable when its dock lies outside the arena or the robot body would cross a wall
        there (``dock_depth`` < ``radius``), when two slots at a corner block each other's way in
        (:meth:`dock_blocks` both ways), or when docked robots' look-ahead points would be closer than
        ``safety_distance`` (``slot_spacing`` too small, or slots on adjacent walls too close at a corner).
        """
        if self.dock_depth < radius:
            raise ValueError(f"charger slots are unreachable: dock_depth {self.dock_depth} m is less than the robot "
                             f"radius {radius} m (the body would be inside the wall)")
        docks = self.dock_poses()
        if len(docks) == 0:
            raise ValueError(f"no charger slot fits on walls {self.walls} of the arena {self.bounds}")
        x0, x1, y0, y1 = check_bounds(bounds, "arena bounds")
        out = ((docks[:, 0] - radius < x0) | (docks[:, 0] + radius > x1) | (docks[:, 1] - radius < y0)
               | (docks[:, 1] + radius > y1))
        if out.any():
            k = int(np.flatnonzero(out)[0])
            raise ValueError(f"charger slot {k} at ({docks[k, 0]:.3f}, {docks[k, 1]:.3f}) m is unreachable: "
                             f"it lies outside the arena {tuple(bounds)}")
        pts = docks[:, :2] + lookahead * np.column_stack((np.cos(docks[:, 2]), np.sin(docks[:, 2])))
        if len(pts) > 1:
            from scipy.spatial import cKDTree

            pairs = cKDTree(pts).query_pairs(safety_distance, output_type="ndarray")
            if len(pairs):
                i, j = (int(v) for v in pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))][0])
                gap = float(np.hypot(*(pts[i] - pts[j])))
                raise ValueError(f"charger slots {i} and {j} are unreachable together: robots docked there would have "
                                 f"look-ahead points {gap:.3f} m apart, less than the safety distance {safety_distance} m "
                                 f"(raise slot_spacing or corner_clearance)")
        blocks = self.dock_blocks(lookahead, safety_distance)
        mutual = np.argwhere(np.triu(blocks & blocks.T))
        if len(mutual):
            i, j = (int(v) for v in mutual[0])
            raise ValueError(f"charger slots {i} and {j} are unreachable together: a robot docked on either blocks "
                             f"the way onto the other (raise corner_clearance)")
