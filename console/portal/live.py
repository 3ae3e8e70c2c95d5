"""The live view's picture of a running job: one Frame as the JSON the portal's canvas draws.

:func:`scene_message` gives what the console's scene shows of a Frame, read-only
and in plain JSON, drawn with the scene's own helpers
(:mod:`swarmdeck.console.web.scene`: ``robot_colors`` for the state colours,
``h_colors`` for the active barrier pairs, ``heatmap`` for the density) so the
portal's live view, the console and the video (:mod:`~swarmdeck.console.recording.export_video`)
colour a run the same way. Keys (units m, s, rad; N robots, E Voronoi edges, K
active pairs)::

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

A message is a few kB (N = 12); the pages send at most ten a second.
"""
from __future__ import annotations

import base64
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.web.scene import h_colors, heatmap, robot_colors

DENSITY_PX_PER_M = 20.0  # the canvas smooths the small image up; 64 × 40 px on the default arena


def _hex(colours: NDArray[np.uint8]) -> list[str]:
    return [f"#{int(r):02x}{int(g):02x}{int(b):02x}" for r, g, b in colours.reshape(-1, 3)]


def _num(x: float) -> float | None:
    return float(x) if math.isfinite(x) else None


def density_png(frame: Frame, px_per_m: float = DENSITY_PX_PER_M) -> str | None:
    """The Frame's density as the console's heat map, a PNG data URL (None without a density)."""
    if frame.density is None:
        return None
    import cv2

    img = heatmap(frame.density, frame.bounds, px_per_m)
    ok, buf = cv2.imencode(".png", np.ascontiguousarray(img[..., ::-1]))
    return "data:image/png;base64," + base64.b64encode(buf.tobytes()).decode("ascii") if ok else None


def scene_message(frame: Frame, seq: int) -> dict[str, Any]:
    """The JSON-able picture of ``frame`` (module docstring)."""
    b, cov = frame.barrier, frame.coverage
    pairs = np.empty((0, 2), dtype=np.int64)
    pair_colours: list[str] = []
    moved: list[int] = []
    barrier = None
    if b is not None:
        if len(b.active_pairs) and b.active_pairs.max() < frame.n:
            pairs = b.active_pairs
            pair_colours = _hex(h_colors(b.active_h, b.safety_distance)[:, 0, :])
        if len(b.intervention) == frame.n:
            moved = np.flatnonzero(b.intervention > 1e-3).tolist()
        barrier = {"enabled": b.enabled, "ok": b.ok, "n_active": b.n_active,
                   "min_distance": _num(b.min_distance), "safety_distance": b.safety_distance}
    return {
        "seq": int(seq), "tick": frame.tick, "t": round(frame.run_time, 3), "run_state": frame.run_state,
        "bounds": list(frame.bounds), "ids": frame.ids.tolist(),
        "poses": np.round(frame.poses, 4).tolist(), "colours": _hex(robot_colors(frame)),
        "points": np.round(frame.points, 4).tolist(), "moved": moved,
        "virtual": np.flatnonzero(frame.is_virtual).tolist(),
        "edges": np.round(cov.edges, 3).tolist() if cov is not None else [],
        "centroids": np.round(cov.centroids, 3).tolist() if cov is not None else [],
        "pairs": pairs.tolist(), "pair_colours": pair_colours, "barrier": barrier,
        "density": density_png(frame), "events": list(frame.events),
    }
