"""rps.utilities.misc: initial conditions and arrival tests, in rps's column layout."""
from __future__ import annotations

import numpy as np

from swarmdeck.core.bounds import Bounds
from swarmdeck.devices.controllers import at_pose as _at_pose
from swarmdeck.devices.controllers import at_position as _at_position
from swarmdeck.devices.initial_conditions import random_initial_poses


def generate_initial_conditions(N: int, spacing: float = 0.3, width: float = 3, height: float = 1.8) -> np.ndarray:
    """(3, N) random float poses at least ``spacing`` apart in a width × height box at the centre — drawn from
    numpy's global generator, as rps draws them, so a script that calls ``np.random.seed`` gets the same poses on
    every run."""
    bounds = Bounds(-width / 2, width / 2, -height / 2, height / 2)
    rng = np.random.default_rng(np.random.randint(0, 2**63 - 1, dtype=np.int64))
    return random_initial_poses(N, bounds, spacing=spacing + 0.01, min_separation=spacing, wall_margin=0.0, rng=rng).T


def at_pose(states, poses, position_error: float = 0.05, rotation_error: float = 0.2) -> tuple[np.ndarray, ...]:
    """Indices of robots at their goal pose (as rps: ``np.nonzero(...)``)."""
    return np.nonzero(_at_pose(np.asarray(states, dtype=float).T, np.asarray(poses, dtype=float).T,
                               position_error, rotation_error))


def at_position(states, points, position_error: float = 0.02) -> tuple[np.ndarray, ...]:
    """Indices of robots at their goal position."""
    return np.nonzero(_at_position(np.asarray(states, dtype=float)[:2].T, np.asarray(points, dtype=float)[:2].T,
                                   position_error))


def _points_per_metre(robotarium) -> float | None:
    """Typographic points per arena metre on ``robotarium``'s (headless) figure, None without one."""
    axes = getattr(robotarium, "axes", None)
    if axes is None:
        return None
    origin, unit = axes.transData.transform([[0.0, 0.0], [1.0, 0.0]])
    return abs(float(unit[0] - origin[0])) * 72.0 / axes.figure.dpi


def determine_marker_size(robotarium, marker_size_meters: float) -> float:
    """rps: the ``scatter`` size (points², an area) of a marker ``marker_size_meters`` m across on the figure —
    what is drawn on the arena then is that many metres across (``swarmdeck.devices.rps.figure_annotations``)."""
    per_m = _points_per_metre(robotarium)
    return float(marker_size_meters) if per_m is None else (float(marker_size_meters) * per_m) ** 2


def determine_font_size(robotarium, font_height_meters: float) -> float:
    """rps: the font size (points) of text ``font_height_meters`` m tall on the figure (and on the arena)."""
    per_m = _points_per_metre(robotarium)
    return float(font_height_meters) if per_m is None else float(font_height_meters) * per_m


# rps 2.0's names (rps/utilities/misc.py on `master`)
def generate_random_poses(N: int, spacing: float = 0.5, width: float = 3.0, height: float = 1.8) -> np.ndarray:
    """rps 2.0: (3, N) random float poses at least ``spacing`` apart in a width × height box at the centre."""
    return generate_initial_conditions(N, spacing=spacing, width=width, height=height)


def generate_random_positions(N: int, spacing: float = 0.5, width: float = 3.0, height: float = 1.8) -> np.ndarray:
    """rps 2.0: (2, N) random positions at least ``spacing`` apart."""
    return generate_random_poses(N, spacing, width, height)[:2]


def generate_initial_poses(N: int, width: float = 3.0, height: float = 1.0) -> np.ndarray:
    """rps 2.0: (3, N) poses where robots come off the chargers: N of 22 slots on two lines (11 across
    ``width`` at y = ±height/2), facing into the arena, chosen at random."""
    xs = np.linspace(-width / 2, width / 2, 11)
    slots = np.array([[x, y, np.pi / 2 if y < 0 else -np.pi / 2] for x in xs for y in (-height / 2, height / 2)])
    if not 1 <= N <= len(slots):
        raise ValueError(f"generate_initial_poses places 1 to {len(slots)} robots, got N={N!r}")
    return slots[np.random.choice(len(slots), size=N, replace=False)].T


def create_at_pose(position_error: float = 0.05, rotation_error: float = 0.2):
    """rps 2.x: f(states (3, N), poses (3, N)) → (all robots there, (N,) bool: which are there) — a mask, as
    rps 2.x returns (its examples combine it with ``&`` and ``~``), not 1.x's indices."""

    def check_at_pose(states, poses):
        states = np.asarray(states, dtype=float)
        there = np.zeros(states.shape[1], dtype=bool)
        there[at_pose(states, poses, position_error, rotation_error)[0]] = True
        return bool(there.all()), there

    return check_at_pose


def create_at_position(position_error: float = 0.05):
    """rps 2.x: f(states (2+, N), positions (2, N)) → (all robots there, (N,) bool: which are there)."""

    def check_at_position(states, positions):
        states = np.asarray(states, dtype=float)
        there = np.zeros(states.shape[1], dtype=bool)
        there[at_position(states, positions, position_error)[0]] = True
        return bool(there.all()), there

    return check_at_position


def rotation_matrix(theta: float) -> np.ndarray:
    """The 2 × 2 rotation by ``theta`` rad."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s], [s, c]])


def unique_filename(file_name: str) -> str:
    """rps 2.0: ``file_name`` with the current time, ``.npy``."""
    from datetime import datetime

    return f"{file_name}_{datetime.now().strftime('%Y_%m_%d_%H_%M_%S')}.npy"


def __getattr__(name: str):
    """``plt`` (``from rps.utilities.misc import *`` gives it to rps scripts): matplotlib's pyplot on a
    headless backend, loaded on first use so scripts that never plot do not pay for it."""
    if name == "plt":
        from swarmdeck.devices.rps.figure import pyplot

        return pyplot()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# rps's misc does `import numpy as np` and `import matplotlib.pyplot as plt`, and scripts get both
# from `from rps.utilities.misc import *` (some rps examples never import numpy themselves).
__all__ = ["at_pose", "at_position", "create_at_pose", "create_at_position", "determine_font_size",
           "determine_marker_size", "generate_initial_conditions", "generate_initial_poses", "generate_random_poses", "generate_random_positions",
           "np", "plt", "rotation_matrix", "unique_filename"]
