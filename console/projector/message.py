"""The projector's picture of one Frame: the layers the operator chose, as the JSON the projector page draws.

:func:`projector_message` serialises the renderer-neutral picture of the Frame
(:func:`~swarmdeck.console.picture.picture.picture_of`) layer by layer, keeping only the layers switched on in
:class:`~swarmdeck.console.runtime.params.ProjectorParams` (a layer switched off costs nothing to send or draw).
Keys (units m, s, rad; N robots, E Voronoi edges, C centroids, G goals)::

    seq, tick, t     the feed's sequence number, the Frame's tick and run time s
    stamp            wall-clock time the loop handed the Frame over, ms since the epoch (tick → pixels latency)
    run_state        "running" | "paused" | "estop"
    bounds           [x_min, x_max, y_min, y_max]
    n                number of robots N
    density          null | {w, h, rgb}: the console's heat map covering ``bounds`` (row 0 at y_max), w × h px,
                     ``rgb`` the raw RGB bytes row by row, base64 (no image to decode: the page puts the pixels)
    edges            (E, 2, 2) Voronoi edges          — layer "cells"
    centroids        (C, 2)                           — layer "centroids"
    goals            (G, 2) goto goals                — layer "goals"
    halos            {xy (N, 2), palette [C] "#rrggbb", colour (N,) index into palette, radius m} — layer "halos"
    safety           {xy (N, 2) look-ahead points, radius D_s / 2 m} — layer "safety"
    graph            null | {segments (L, 2, 2) m, colours (L,) "#rrggbb"}: the communication graph, when the
                     picture has one (``Picture.network``, a NetworkLayer) — layer "graph"
    annotations      null | the experiment's drawings as ``console.picture.annotations.annotations_json`` gives
                     them ({kinds, offsets, vertices m, sizes m, colours, filled, texts}), when the picture has
                     them (``Picture.annotations``) — layer "annotations"
    palette          the picture's colours (``console.portal.live.PALETTE``)

The page learns the homography, the projector's size and the settings from the stream's ``config`` event
(:func:`config_message`).
"""
from __future__ import annotations

import base64
from typing import Any

import numpy as np

from swarmdeck.console.picture.annotations import annotations_json
from swarmdeck.console.picture.colours import hex_colors
from swarmdeck.console.picture.network import NetworkLayer
from swarmdeck.console.picture.picture import picture_of
from swarmdeck.console.portal.live import PALETTE
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.params import ProjectorParams, to_dict
from swarmdeck.core.annotations import Annotations
from swarmdeck.core.bounds import Bounds
from swarmdeck.core.constants import ROBOT_RADIUS
from swarmdeck.tracking.projector import ProjectorCalibration

#: Heat-map sampling of the projected density, px per m (the page smooths it up).
DENSITY_PX_PER_M = 25.0
#: A robot's halo radius, × the robot's radius.
HALO_SCALE = 1.6


def _xy(a: Any, digits: int = 3) -> list[Any]:
    return np.round(np.asarray(a, dtype=float), digits).tolist()


def projector_message(frame: Frame, seq: int, settings: ProjectorParams, stamp_ms: float) -> dict[str, Any]:
    """The JSON-able projector picture of ``frame`` with the layers ``settings`` switches on (module docstring)."""
    pic = picture_of(frame)
    s = settings
    msg: dict[str, Any] = {
        "seq": int(seq), "tick": int(frame.tick), "t": round(float(frame.run_time), 3), "stamp": float(stamp_ms),
        "run_state": pic.run_state, "bounds": list(pic.bounds), "n": pic.n, "palette": PALETTE,
        "density": None, "edges": [], "centroids": [], "goals": [], "halos": None, "safety": None,
        "graph": None, "annotations": None,
    }
    if s.blackout:
        return msg
    if s.density:
        heat = pic.heat_map(DENSITY_PX_PER_M)
        if heat is not None:
            msg["density"] = {"w": int(heat.shape[1]), "h": int(heat.shape[0]),
                              "rgb": base64.b64encode(np.ascontiguousarray(heat).tobytes()).decode("ascii")}
    if s.cells and frame.coverage is not None:
        msg["edges"] = _xy(pic.edges)
    if s.centroids and frame.coverage is not None:
        msg["centroids"] = _xy(pic.centroids)
    if s.goals:
        msg["goals"] = _xy(pic.goals)
    if s.halos:
        palette, index = np.unique(np.asarray(pic.colors, dtype=np.uint8).reshape(-1, 3), axis=0, return_inverse=True)
        msg["halos"] = {"xy": _xy(pic.poses[:, :2]), "palette": hex_colors(palette),
                        "colour": np.asarray(index).reshape(-1).tolist(), "radius": HALO_SCALE * ROBOT_RADIUS}
    if s.safety:
        msg["safety"] = {"xy": _xy(pic.points), "radius": float(pic.ring_radius)}
    if s.graph:
        msg["graph"] = _graph(pic.network)
    if s.annotations:
        msg["annotations"] = _annotations(pic.annotations)
    return msg


def _graph(layer: NetworkLayer | None) -> dict[str, Any] | None:
    """The communication graph (the picture's ``network``: a NetworkLayer with ``segments`` (L, 2, 2) m and
    ``colors`` (L, 3) uint8), or None when the picture has none (a Frame without a network)."""
    if layer is None or not len(layer.segments):
        return None
    return {"segments": _xy(layer.segments), "colours": hex_colors(np.asarray(layer.colors, dtype=np.uint8))}


def _annotations(ann: Annotations) -> dict[str, Any] | None:
    """The experiment's drawings (the picture's ``annotations``) in the canvases' one JSON form, or None when
    there are none."""
    if not len(ann):
        return None
    return annotations_json(ann)


def config_message(bounds: Bounds, calibration: ProjectorCalibration | None, settings: ProjectorParams,
                   version: int) -> dict[str, Any]:
    """The page's configuration: the arena ``bounds``, the homography ``H`` (3 × 3 floor m → projector px, or
    null: the page says "no homography — run swarmdeck calibrate projector" on the floor), the projector's
    ``size`` [w, h] px, the ``settings`` (:class:`ProjectorParams` as a dict) and their ``version``."""
    return {"bounds": list(bounds), "version": int(version), "settings": to_dict(settings),
            "H": None if calibration is None else calibration.homography.tolist(),
            "size": None if calibration is None else list(calibration.size),
            "palette": PALETTE}
