"""Which robots a job gets and where they start: the one rule the arena runner and verification share.

A script asks for its Arena with ``n`` robots and, optionally, its own initial conditions (the
poses it passes to ``Arena(…, initial_conditions=…)`` / ``Robotarium(initial_conditions=…)``).
:func:`arena_start` decides, in this order:

1. ``n`` must be the declared count (the manifest's ``robots``; ``swarmdeck verify --robots N``):
   anything else is refused at once, before any robot is simulated or set up;
2. the start poses are the manifest's ``initial_poses``, else the script's initial conditions
   (checked like the manifest's: :func:`check_initial_poses`), else random valid ones (the
   caller's generator: the arena's fleet keeps them clear of its chargers).

The arena sets its robots up at those poses within the fleet's set-up tolerance
(:data:`~swarmdeck.devices.fleet.setup.ACCEPT_POSITION`, 2 cm, and
:data:`~swarmdeck.devices.fleet.setup.ACCEPT_HEADING`, 5°); verification starts every run from
them plus a seeded random error within that tolerance (:func:`perturb`), so it checks what the
arena will run.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.kinematics import wrap_angle
from swarmdeck.devices.fleet.setup import ACCEPT_HEADING, ACCEPT_POSITION
from swarmdeck.devices.simulator import check_poses

#: m between the centres of two initial poses: the look-ahead points (ℓ = 0.03 m) start outside
#: D_s = 0.17 m whatever the headings (``devices.initial_conditions``).
MIN_SEPARATION = 0.23
SOURCES = ("manifest", "script", "random")


def check_initial_poses(poses: ArrayLike, n: int, bounds: Bounds = DEFAULT_BOUNDS,
                        name: str = "initial_poses", *, first: int = 0) -> NDArray[np.float64]:
    """Validated copy of ``n`` initial poses ``(n, 3)`` [x, y, θ] (m, rad): finite floats, every centre
    inside ``bounds``, centres pairwise at least :data:`MIN_SEPARATION` apart. ValueError naming the
    first bad pose (``name`` says whose poses they are: the manifest's, the script's; poses are numbered
    from ``first``: 0 for a script's array rows, 1 where people count them, as the portal does)."""
    arr = np.asarray(poses)
    if arr.dtype.kind in "iu":
        arr = arr.astype(float)  # JSON has no int/float distinction: 0 means 0.0 here
    arr = check_poses(arr, name, n)
    x0, x1, y0, y1 = bounds
    outside = np.flatnonzero((arr[:, 0] < x0) | (arr[:, 0] > x1) | (arr[:, 1] < y0) | (arr[:, 1] > y1))
    if len(outside):
        k = int(outside[0])
        raise ValueError(f"{name}: pose {k + first} ({arr[k, 0]:.3f}, {arr[k, 1]:.3f}, {arr[k, 2]:.3f}) is outside the "
                         f"arena {tuple(bounds)}")
    if len(arr) >= 2:
        pairs = cKDTree(arr[:, :2]).query_pairs(MIN_SEPARATION - 1e-9, output_type="ndarray")
        if len(pairs):
            i, j = (int(v) for v in pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))][0])
            gap = float(np.hypot(*(arr[i, :2] - arr[j, :2])))
            raise ValueError(f"{name}: poses {i + first} ({arr[i, 0]:.3f}, {arr[i, 1]:.3f}) and {j + first} "
                             f"({arr[j, 0]:.3f}, "
                             f"{arr[j, 1]:.3f}) are {gap:.3f} m apart; initial positions must be at least "
                             f"{MIN_SEPARATION} m apart")
    return arr


@dataclass(frozen=True)
class ArenaStart:
    """What :func:`arena_start` decided: ``poses`` ``(N, 3)`` and where they came from (:data:`SOURCES`)."""

    poses: NDArray[np.float64]
    source: str


def arena_start(n_script: int, declared: int | None, manifest_poses: ArrayLike | None,
                script_poses: ArrayLike | None, random_poses: Callable[[int], NDArray[np.float64]],
                bounds: Bounds = DEFAULT_BOUNDS, *, declared_by: str = "the manifest") -> ArenaStart:
    """The robots and start poses of an Arena the script asked for (module docstring).

    Args:
        n_script: robots the script's Arena asks for.
        declared: the declared count (None: nothing declared, the script's count is taken).
        manifest_poses: the manifest's ``initial_poses`` ``(N, 3)`` or None.
        script_poses: the script's own initial conditions ``(n_script, 3)`` or None.
        random_poses: ``random_poses(n)`` → ``(n, 3)`` valid random poses.
        bounds: the arena, m.
        declared_by: who declared the count, for the message ("the manifest", "--robots").

    Raises:
        ValueError: the script asks for another count than declared, or its (or the manifest's)
            poses are invalid; the message names the count or the pose.
    """
    if declared is not None and n_script != declared:
        raise ValueError(f"the script asks for {n_script} robots but {declared_by} declares {declared}")
    if manifest_poses is not None:
        return ArenaStart(check_initial_poses(manifest_poses, n_script, bounds, "the manifest's initial_poses"),
                          "manifest")
    if script_poses is not None:
        return ArenaStart(check_initial_poses(script_poses, n_script, bounds, "the script's initial conditions"),
                          "script")
    return ArenaStart(np.asarray(random_poses(n_script), dtype=float), "random")


def perturb(poses: ArrayLike, rng: np.random.Generator, position: float = ACCEPT_POSITION,
            heading: float = ACCEPT_HEADING) -> NDArray[np.float64]:
    """``poses`` ``(N, 3)`` plus a set-up error within the fleet's tolerance: each centre moved uniformly
    within a disc of radius ``position`` m, each heading by up to ±``heading`` rad (a new array)."""
    p = np.array(poses, dtype=float, copy=True)
    n = len(p)
    r = position * np.sqrt(rng.uniform(0.0, 1.0, n))
    a = rng.uniform(-np.pi, np.pi, n)
    p[:, 0] += r * np.cos(a)
    p[:, 1] += r * np.sin(a)
    p[:, 2] = wrap_angle(p[:, 2] + rng.uniform(-heading, heading, n))
    return p
