"""The palette every renderer of a Frame uses: RGB 0–255, one name per meaning.

The viser scene, the video, the Foxglove channels and the portal's live view all
take their colours from here (through :func:`~swarmdeck.console.picture.picture.picture_of`
or directly), so a robot, an active barrier pair or a Voronoi edge has the same colour
wherever it is drawn. Arrays are read-only.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def _rgb(*values: int) -> NDArray[np.uint8]:
    a = np.array(values, dtype=np.uint8).reshape(-1, 3) if len(values) > 3 else np.array(values, dtype=np.uint8)
    a.flags.writeable = False
    return a


# robots by state (:func:`~swarmdeck.console.picture.picture.robot_colors`)
ROBOT = _rgb(20, 70, 170)
"""a robot running normally: blue"""
CHANGED = _rgb(255, 140, 0)
"""a robot whose command the barrier changed (and the ring drawn round it): orange"""
STOPPED = _rgb(210, 30, 30)
"""every robot during an emergency stop (and the e-stop frame/banner): red"""
PAUSED = _rgb(90, 110, 140)
"""every robot while paused: slate"""
UNSEEN = _rgb(160, 160, 160)
"""a robot the camera did not see this tick: grey"""
VIRTUAL_PALE = 0.55
"""virtual robots' colours are blended this much toward white"""
VIRTUAL_RING = (120, 60, 200)
"""the dashed ring round a virtual robot: violet"""

# the floor and its overlays
BOUNDARY = (40, 40, 40)
"""the arena outline"""
VORONOI = (60, 60, 60)
"""Voronoi edges"""
OBSTACLE = (110, 70, 30)
"""line-segment obstacles on the floor (core.obstacles): dark brown, drawn thick"""
CENTROID = (200, 30, 60)
"""cell centroids"""
CONTACT = (200, 0, 200)
"""touch contacts"""
GOAL = (30, 150, 70)
"""goals of the goto behaviour"""
PAIR = (230, 40, 20)
"""an active barrier pair at h ≤ 0 (the ramp's red end; :func:`pair_colors`)"""
LABEL = (25, 25, 25)
"""robot id labels"""
HEADING = (255, 255, 255)
"""the heading tick on a robot"""
SAFETY_RING = (120, 120, 120)
"""the safety ring (radius D_s / 2) round every look-ahead point"""
NOMINAL = (130, 130, 130)
"""the nominal command's arrow"""
SAFE = (20, 150, 60)
"""the safe (certified) command's arrow"""

#: communication links (console/picture/network.py): idle (nothing crossed this tick) → busy
LINK_IDLE = (175, 190, 215)
LINK_BUSY = (0, 150, 200)
#: bar colours by battery level (LEVELS of console.runtime.batteries: unknown, low, fair, good, charging)
BATTERY_COLORS = _rgb(160, 160, 160, 220, 30, 30, 235, 160, 20, 40, 170, 60, 40, 120, 230)
BATTERY_TRACK = _rgb(200, 200, 200)

# Heat map colours (low → high φ): near-white → light orange → red-orange.
_LUT_STOPS = np.array([[250, 250, 246], [254, 227, 180], [253, 174, 97], [227, 74, 51]], dtype=float)


def _lut() -> NDArray[np.uint8]:
    x = np.linspace(0.0, 1.0, 256)
    xp = np.linspace(0.0, 1.0, len(_LUT_STOPS))
    lut = np.column_stack([np.interp(x, xp, _LUT_STOPS[:, c]) for c in range(3)]).astype(np.uint8)
    lut.flags.writeable = False
    return lut


LUT = _lut()
"""(256, 3) heat-map colour map, index = round-down of 255 φ / max φ"""


def pair_colors(h: NDArray[np.float64], h_full: float = 0.1) -> NDArray[np.uint8]:
    """(K, 3) colours of active barrier pairs by their barrier value h (m²): red (:data:`PAIR`) at h ≤ 0
    → yellow at h ≥ ``h_full``."""
    s = np.clip(np.asarray(h, dtype=float) / h_full, 0.0, 1.0)
    return np.column_stack((np.full_like(s, 230), 40 + 180 * s, 20 + 20 * s)).astype(np.uint8)


def hex_colors(colours: NDArray[np.uint8]) -> list[str]:
    """``"#rrggbb"`` of every colour in ``colours`` (…, 3), for HTML canvases."""
    return [f"#{int(r):02x}{int(g):02x}{int(b):02x}" for r, g, b in np.asarray(colours).reshape(-1, 3)]

# ---------------------------------------------------------------- the sensors' layer (issue 28.1)
#: A ToF ray from its sensor to what it hit.
SENSOR_RAY = (0, 150, 160)
#: Where a ToF reading ends.
SENSOR_HIT = (0, 110, 120)

#: One colour per run when several recordings are shown together (``swarmdeck play A B …``, the portal's
#: comparison): run 1 (solid) the robots' blue, the others (ghosts) in turn; cycles after eight runs.
RUN_COLORS = _rgb(20, 70, 170, 214, 39, 40, 44, 160, 44, 148, 103, 189, 255, 127, 14, 23, 190, 207,
                  140, 86, 75, 227, 119, 194)
