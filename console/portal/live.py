"""The live view's picture of a running job: one Frame as the JSON the portal's canvas draws.

:func:`scene_message` is a serialisation of the renderer-neutral picture of the Frame
(:func:`~swarmdeck.console.picture.picture.picture_of`), the same the console's scene, the
video and the Foxglove channels draw: ``colours``, ``moved``, ``pairs``/``pair_colours`` and
``virtual`` are the picture's robot colours, changed robots, active pairs and virtual robots,
and ``palette``/``robot_radius``/``rings`` give ``static/live.js`` the picture's colours and
glyph sizes, so the canvas hard-codes none of them. Keys (units m, s, rad; N robots, E Voronoi
edges, K active pairs)::

    seq          int, the LiveFeed's sequence number of this Frame
    tick, t      tick index; run time s (the behaviours' clock: what the script sees)
    run_state    "running" | "paused" | "estop"
    bounds       [x_min, x_max, y_min, y_max]
    ids          (N,) robot ids
    poses        (N, 3) [x, y, θ], rounded to 0.1 mm / 0.1 mrad
    colours      (N,) "#rrggbb" by state (blue, orange: the filter changed the command, red: e-stop, …)
    points       (N, 2) look-ahead points
    moved        indices of the robots whose command the filter changed
    virtual      indices of the virtual robots (simulated beside the physical ones: a dashed violet ring)
    edges        (E, 2, 2) Voronoi edges, or [] when the behaviour has no cells
    centroids    (N, 2) or []
    pairs        (K, 2) active barrier pairs (look-ahead point indices); pair_colours (K,) "#rrggbb" by h
    barrier      null | {enabled, ok, n_active, min_distance, safety_distance}
    density      null | "data:image/png;base64,…" the heat map, row 0 at y_max, covering ``bounds``
    events       [str] messages of this tick
    robot_radius body radius of the robot glyph, m
    rings        {"changed": …, "virtual": …} ring radii round changed / virtual robots, × robot_radius
    palette      {floor, grid, boundary, voronoi, centroid, changed, virtual, label, heading, stopped, sensor_ray,
                 sensor_hit}: "#rrggbb"
    sensors      only when the Frame has sensors (the picture's sensor layer): {rays (R, 2, 2) ToF rays from
                 sensor to end point, rounded to 1 mm; leds (N,) "#rrggbb" or null for an unlit LED}

A message is a few kB (N = 12); the pages send at most ten a second.
"""
from __future__ import annotations

import base64
import math
from typing import Any

import numpy as np

from swarmdeck.console.picture import colours as pal
from swarmdeck.console.picture.picture import Picture, picture_of
from swarmdeck.console.picture.shapes import CHANGED_RING, VIRTUAL_RING_RADIUS
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.core.constants import ROBOT_RADIUS

DENSITY_PX_PER_M = 20.0  # the canvas smooths the small image up; 64 × 40 px on the default arena

PALETTE: dict[str, str] = dict(zip(
    ("floor", "grid", "boundary", "voronoi", "centroid", "changed", "virtual", "label", "heading", "stopped",
     "sensor_ray", "sensor_hit"),
    pal.hex_colors(np.array([pal.LUT[0], (150, 150, 150), pal.BOUNDARY, pal.VORONOI, pal.CENTROID, pal.CHANGED,
                             pal.VIRTUAL_RING, pal.LABEL, pal.HEADING, pal.STOPPED, pal.SENSOR_RAY, pal.SENSOR_HIT],
                            dtype=np.uint8)),
    strict=True))
"""the picture's colours as the canvas needs them (``palette`` of every message)"""


def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def density_png(picture: Picture | Frame, px_per_m: float = DENSITY_PX_PER_M) -> str | None:
    """The density as the console's heat map, a PNG data URL (None without a density)."""
    if picture.density is None:
        return None
    import cv2

    from swarmdeck.console.picture.heat import heatmap

    img = heatmap(picture.density, picture.bounds, px_per_m)
    ok, buf = cv2.imencode(".png", np.ascontiguousarray(img[..., ::-1]))
    return "data:image/png;base64," + base64.b64encode(buf.tobytes()).decode("ascii") if ok else None


def scene_message(frame: Frame, seq: int) -> dict[str, Any]:
    """The JSON-able picture of ``frame`` (module docstring)."""
    pic = picture_of(frame)
    b = frame.barrier
    barrier = None
    if b is not None:
        barrier = {"enabled": b.enabled, "ok": b.ok, "n_active": b.n_active,
                   "min_distance": _num(b.min_distance), "safety_distance": b.safety_distance}
    message = {
        "seq": int(seq), "tick": frame.tick, "t": round(frame.run_time, 3), "run_state": pic.run_state,
        "bounds": list(pic.bounds), "ids": pic.ids.tolist(),
        "poses": np.round(pic.poses, 4).tolist(), "colours": pal.hex_colors(pic.colors),
        "points": np.round(pic.points, 4).tolist(), "moved": np.flatnonzero(pic.changed).tolist(),
        "virtual": np.flatnonzero(pic.virtual).tolist(),
        "edges": np.round(pic.edges, 3).tolist() if frame.coverage is not None else [],
        "centroids": np.round(pic.centroids, 3).tolist() if frame.coverage is not None else [],
        "pairs": pic.pairs.tolist(), "pair_colours": pal.hex_colors(pic.pair_colors), "barrier": barrier,
        "density": density_png(pic), "events": list(pic.events),
        "robot_radius": ROBOT_RADIUS, "rings": {"changed": CHANGED_RING, "virtual": VIRTUAL_RING_RADIUS},
        "palette": PALETTE,
    }
    if pic.sensors is not None:  # the sensors' layer, only when the Frame has sensors
        layer = pic.sensors
        leds = None
        if layer.leds is not None:
            hexes = pal.hex_colors(layer.leds)
            leds = [h if on else None for h, on in zip(hexes, layer.led_on.tolist())]
        message["sensors"] = {"rays": np.round(np.stack((layer.ray_starts, layer.ray_ends), axis=1), 3).tolist(),
                              "leds": leds}
    return message
