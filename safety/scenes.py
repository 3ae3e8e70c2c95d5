"""Random test and benchmark scenes (REFERENCE.md §3 "dense random scenes").

Robots on a random subset of a jittered grid whose pitch is just wider than
D_s, every point inside the wall margin, with random nominal directions and
speeds up to v_max.
"""
from __future__ import annotations

import math

import numpy as np

from swarmdeck.core.bounds import Bounds

from .config import BarrierConfig


def arena_for(n: int, pitch: float, fill: float = 0.8, aspect: float = 1.6,
              margin: float = 0.095) -> Bounds:
    """A centred arena (x_min, x_max, y_min, y_max) whose grid holds n robots at ``fill`` occupancy."""
    cells = n / fill
    rows = math.ceil(math.sqrt(cells / aspect))
    cols = math.ceil(cells / rows)
    half_w = (cols - 1) * pitch / 2 + margin + 1e-3
    half_h = (rows - 1) * pitch / 2 + margin + 1e-3
    return Bounds(-half_w, half_w, -half_h, half_h)


def grid_scene(n: int, rng: np.random.Generator, cfg: BarrierConfig | None = None,
               pitch: float | None = None, jitter: float = 0.004) -> tuple[np.ndarray, np.ndarray]:
    """(points (n, 2), nominal (n, 2)) on a jittered grid inside ``cfg.bounds``.

    pitch defaults to D_s + 2·jitter + 0.01 m, so every pair starts ≥ D_s + 0.01
    apart; points keep ≥ margin + jitter from the walls. Raises ValueError when
    the arena cannot hold n robots at that pitch.
    """
    cfg = BarrierConfig() if cfg is None else cfg
    pitch = cfg.safety_distance + 2 * jitter + 0.01 if pitch is None else pitch
    x_min, x_max, y_min, y_max = cfg.bounds
    inset = cfg.margin + jitter + 1e-6
    xs = np.arange(x_min + inset, x_max - inset + 1e-12, pitch)
    ys = np.arange(y_min + inset, y_max - inset + 1e-12, pitch)
    xs += (x_max - inset - xs[-1]) / 2 if xs.size else 0.0
    ys += (y_max - inset - ys[-1]) / 2 if ys.size else 0.0
    X, Y = np.meshgrid(xs, ys)
    cells = np.stack([X.ravel(), Y.ravel()], axis=1)
    if cells.shape[0] < n:
        raise ValueError(f"grid_scene: the arena {cfg.bounds} holds {cells.shape[0]} robots at pitch {pitch}, not {n}")
    pts = cells[rng.permutation(cells.shape[0])[:n]] + rng.uniform(-jitter, jitter, (n, 2))
    ang = rng.uniform(0, 2 * np.pi, n)
    speed = rng.uniform(0, cfg.max_speed, n)
    nominal = np.stack([np.cos(ang), np.sin(ang)], axis=1) * speed[:, None]
    return pts, nominal


def crossing_scene(n: int, rng: np.random.Generator, fill: float = 0.5, pitch: float = 0.188
                   ) -> tuple[BarrierConfig, np.ndarray, np.ndarray]:
    """(config, points (n, 2) m, goals (n, 2) m) of the dense crossing (issue 27): n robots on a
    jittered grid at ``fill`` occupancy of an arena sized for them, each bound for its point
    reflected through the centre, so the swarm swaps through the middle and jams there."""
    cfg = BarrierConfig(bounds=arena_for(n, pitch, fill=fill))
    points, _ = grid_scene(n, rng, cfg, pitch=pitch)
    return cfg, points, -points


def toward(goals: np.ndarray, points: np.ndarray, max_speed: float) -> np.ndarray:
    """(n, 2) m/s nominal: proportional control (gain 1/s) to ``goals``, capped at ``max_speed``."""
    u = goals - points
    s = np.sqrt(np.einsum("kd,kd->k", u, u))[:, None]
    return u * np.minimum(1.0, max_speed / np.maximum(s, 1e-12))


def jammed_crossing(n: int, seed: int, ticks: int) -> tuple[BarrierConfig, np.ndarray, np.ndarray]:
    """(config, points (n, 2) m, goals (n, 2) m) of :func:`crossing_scene` (``default_rng(seed)``) after
    ``ticks`` ticks of clarabel's trajectory (every robot driven :func:`toward` its goal): a jammed scene
    for tests that need many active rows. ValueError if clarabel fails on a tick."""
    import dataclasses

    from .filter import SafetyFilter

    cfg, x, goals = crossing_scene(n, np.random.default_rng(seed))
    flt = SafetyFilter(dataclasses.replace(cfg, solver="clarabel"))
    for _ in range(ticks):
        u, d = flt.filter(x, toward(goals, x, cfg.max_speed))
        if not d.ok:
            raise ValueError(f"clarabel failed on the crossing (n = {n}, seed = {seed}): {d.status}")
        x = x + u * cfg.dt
    return cfg, x, goals
