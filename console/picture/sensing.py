"""The sensors' layer of the picture (issue 28.1): ToF rays and their end points, and each robot's LED colour.

:func:`sensor_layer` turns a Frame's ``sensors`` (:class:`~swarmdeck.console.runtime.sensors_frame.SensorsFrame`)
into arrays every backend draws: segments from each sensor to where its reading ends (only readings that hit
something: −1 and NaN draw nothing), the end points, and the LEDs. ``PictureStyle.sensors`` switches the layer off;
rays are drawn up to ``style.max_glyphs`` robots, like the other per-robot glyphs. Units m.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.picture.style import PictureStyle
from swarmdeck.console.runtime.frame import Frame

__all__ = ["SensorLayer", "sensor_layer"]


@dataclass(frozen=True)
class SensorLayer:
    """What to draw of the robots' sensors (read-only arrays).

    Attributes:
        ray_starts, ray_ends: ``(R, 2)`` each ToF ray that read something, from its sensor to its end point, m.
        ray_robot: ``(R,)`` the row of the robot each ray belongs to.
        leds: ``(N, 3)`` uint8 LED colours, or None when the Frame has none.
        led_on: ``(N,)`` the LEDs that are lit (not black).
    """

    ray_starts: NDArray[np.float64]
    ray_ends: NDArray[np.float64]
    ray_robot: NDArray[np.int64]
    leds: NDArray[np.uint8] | None
    led_on: NDArray[np.bool_]


def _ro(a: NDArray[Any]) -> Any:
    a = np.array(a, copy=True)
    a.flags.writeable = False
    return a


def sensor_layer(frame: Frame, style: PictureStyle) -> SensorLayer | None:
    """The :class:`SensorLayer` of ``frame``, or None (no sensors in the Frame, or ``style.sensors`` off)."""
    s = frame.sensors
    if s is None or not style.sensors:
        return None
    starts = ends = np.zeros((0, 2))
    robot = np.zeros(0, dtype=np.int64)
    rays = s.rays(frame.poses) if frame.n <= style.max_glyphs else None
    if rays is not None:
        origins, endpoints = rays
        hit = np.isfinite(endpoints).all(axis=-1)
        starts, ends = origins[hit], endpoints[hit]
        robot = np.nonzero(hit)[0].astype(np.int64)
    leds = None if s.leds is None else _ro(s.leds)
    on = np.zeros(frame.n, dtype=bool) if leds is None else np.asarray(leds.any(axis=1), dtype=bool)
    return SensorLayer(ray_starts=_ro(starts), ray_ends=_ro(ends), ray_robot=_ro(robot), leds=leds, led_on=_ro(on))
