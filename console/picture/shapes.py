"""The glyph shapes every renderer draws, in m on the floor (x right, y up): the robot's teardrop and the
rings round a robot. Pure numpy; backends tessellate or rasterise them."""
from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

CHANGED_RING = 1.7
"""radius of the ring round a robot the barrier changed, × robot radius"""
VIRTUAL_RING_RADIUS = 1.35
"""radius of the dashed ring round a virtual robot, × robot radius"""
VIRTUAL_RING_ARCS = 16
"""the virtual ring is 16 arcs, every other one drawn"""


def robot_outline(radius: float) -> NDArray[np.float64]:
    """(23, 2) outline of the robot glyph of body radius ``radius`` m, pointing along +x: a disc from
    35° to 325° closed by a nose at 1.5 radii (a flat teardrop), counter-clockwise."""
    ang = np.linspace(math.radians(35), math.radians(325), 22)
    rim = np.column_stack((radius * np.cos(ang), radius * np.sin(ang)))
    return np.vstack((rim, [[1.5 * radius, 0.0]]))


def dashed_rings(centres: NDArray[np.float64], robot_radius: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The dashed rings round virtual robots at ``centres`` (K, 2) m: dash starts and ends, each (8 K, 2) m
    (every other of :data:`VIRTUAL_RING_ARCS` arcs at :data:`VIRTUAL_RING_RADIUS` robot radii), as chords."""
    a = np.linspace(0, 2 * np.pi, VIRTUAL_RING_ARCS + 1)[:-1]
    r = VIRTUAL_RING_RADIUS * robot_radius
    ring = r * np.column_stack((np.cos(a), np.sin(a)))
    c = np.asarray(centres, dtype=float)[:, None, :]
    return (c + ring[None, ::2, :]).reshape(-1, 2), (c + ring[None, 1::2, :]).reshape(-1, 2)
