"""Random, non-overlapping initial poses for any number of robots that fits.

Robots are placed on a random subset of a hexagonal lattice with spacing
``spacing`` (plus jitter that never brings two robots closer than
``min_separation``), at least ``wall_margin`` from every wall. The lattice fixes
the maximum number of robots in advance, so asking for too many gives an error
naming that maximum instead of a rejection-sampling loop that never ends.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.obstacles import START_CLEARANCE, segments_near


def lattice_sites(bounds: Bounds, spacing: float, wall_margin: float) -> NDArray[np.float64]:
    """Centres ``(M, 2)`` of a hexagonal lattice of pitch ``spacing`` inside the shrunk rectangle."""
    x0, x1, y0, y1 = bounds
    x0, x1, y0, y1 = x0 + wall_margin, x1 - wall_margin, y0 + wall_margin, y1 - wall_margin
    if x1 < x0 or y1 < y0:
        return np.empty((0, 2))
    row_h = spacing * np.sqrt(3.0) / 2.0
    n_rows = int(np.floor((y1 - y0) / row_h + 1e-9)) + 1
    sites = []
    for r in range(n_rows):  # runs once per call, not per tick
        off = 0.5 * spacing * (r % 2)
        xs = np.arange(x0 + off, x1 + 1e-9, spacing)
        sites.append(np.column_stack((xs, np.full_like(xs, y0 + r * row_h))))
    pts = np.vstack(sites) if sites else np.empty((0, 2))
    # Centre the lattice in the rectangle.
    if len(pts):
        pts = pts + np.array([(x0 + x1) / 2 - (pts[:, 0].min() + pts[:, 0].max()) / 2,
                              (y0 + y1) / 2 - (pts[:, 1].min() + pts[:, 1].max()) / 2])
    return pts


def max_robots(
    bounds: Bounds = DEFAULT_BOUNDS, spacing: float = 0.245, min_separation: float = 0.23, wall_margin: float = 0.13
) -> int:
    """The largest N :func:`random_initial_poses` can place with these settings."""
    return int(len(lattice_sites(bounds, spacing, wall_margin + (spacing - min_separation) / 2.0)))


def random_initial_poses(
    n: int,
    bounds: Bounds = DEFAULT_BOUNDS,
    *,
    spacing: float = 0.245,
    min_separation: float = 0.23,
    wall_margin: float = 0.13,
    rng: np.random.Generator | int | None = None,
    avoid: NDArray[np.float64] | None = None,
    obstacles: NDArray[np.float64] | None = None,
    obstacle_clearance: float = START_CLEARANCE,
) -> NDArray[np.float64]:
    """``(n, 3)`` random poses, pairwise at least ``min_separation`` apart (m).

    The default separation 0.23 m keeps the look-ahead points (ℓ = 0.03 m) at
    least D_s = 0.17 m apart whatever the headings, so the safety barrier starts
    in its safe set. ``avoid`` ``(M, 2)`` (m): robots already on the floor (e.g. the
    physical ones beside which virtual robots are placed); every new robot is at
    least ``min_separation`` from each of them too (the maximum then counts only the
    lattice sites left free). ``obstacles`` ``(S, 2, 2)`` (m): line segments
    (:mod:`swarmdeck.core.obstacles`); every robot's centre stays at least
    ``obstacle_clearance`` m from each.

    Raises:
        ValueError: ``n`` < 1, ``min_separation`` > ``spacing``, or more robots than fit
            (the message names the maximum).
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
        raise ValueError(f"number of robots must be an integer, got {n!r}")
    if n < 1:
        raise ValueError(f"number of robots must be >= 1, got {n}")
    if min_separation > spacing:
        raise ValueError(f"min_separation ({min_separation}) must not exceed spacing ({spacing})")
    rng = np.random.default_rng(rng)
    jr = (spacing - min_separation) / 2.0  # jitter radius: keeps pairs >= min_separation apart
    sites = lattice_sites(bounds, spacing, wall_margin + jr)
    if avoid is not None and len(sites):
        others = np.asarray(avoid, dtype=float).reshape(-1, 2)
        others = others[np.all(np.isfinite(others), axis=1)]
        if len(others):
            d = np.linalg.norm(sites[:, None, :] - others[None, :, :], axis=2).min(axis=1)
            sites = sites[d >= min_separation + jr]  # any jitter keeps >= min_separation
    if obstacles is not None and len(obstacles) and len(sites):
        i_near = segments_near(sites, obstacles, obstacle_clearance + jr)[0]  # any jitter keeps the clearance
        sites = np.delete(sites, np.unique(i_near), axis=0)
    if n > len(sites):
        b = Bounds.of(bounds)
        raise ValueError(
            f"{n} robots do not fit in the {b.width:.2f} m x {b.height:.2f} m arena with "
            f"{min_separation} m separation: at most {len(sites)}; use a larger arena or fewer robots"
        )
    chosen = sites[rng.choice(len(sites), size=n, replace=False)]
    ang = rng.uniform(0, 2 * np.pi, n)
    rad = jr * np.sqrt(rng.uniform(0, 1, n))
    xy = chosen + np.column_stack((rad * np.cos(ang), rad * np.sin(ang)))
    theta = rng.uniform(-np.pi, np.pi, n)
    return np.column_stack((xy, theta))
