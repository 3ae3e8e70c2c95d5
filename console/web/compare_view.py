"""Several runs in one player (``swarmdeck play A.mcap B.mcap …``, issue 31 item 4): ghosts and plots per run.

The player (:class:`~swarmdeck.console.web.player.PlayerApp`) draws run A with the console's own
:class:`~swarmdeck.console.web.scene.ArenaScene`. The other runs are drawn

* overlaid (``--layout overlay``): :class:`GhostRobots` — the run's robots as one translucent batched mesh in
  the run's colour (:data:`~swarmdeck.console.picture.colours.RUN_COLORS`) over run A's scene;
* side by side (``--layout side``): a full ``ArenaScene`` each, under the frame node ``/runB``, ``/runC`` …
  moved right by one arena width and a gap per run (:func:`side_offsets`).

:class:`ComparePlots` draws the plots with one line per run, in the runs' colours, against timeline time;
:func:`merge_series` puts the runs' samples on one x axis (each run's value held until its next sample, NaN —
a gap — outside the run).
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.picture.colours import RUN_COLORS, hex_colors
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.web.plots import PlotHistory
from swarmdeck.core.bounds import Bounds
from swarmdeck.core.constants import ROBOT_RADIUS

if TYPE_CHECKING:
    import viser

LAYOUTS: tuple[str, ...] = ("overlay", "side")
GHOST_OPACITY = 0.5
SIDE_GAP = 0.3  # m between the arenas of runs shown side by side


def run_color(i: int) -> tuple[int, int, int]:
    """The colour of run ``i`` (0-based; run 0 is drawn solid in the scene's own colours)."""
    c = RUN_COLORS[i % len(RUN_COLORS)]
    return int(c[0]), int(c[1]), int(c[2])


def side_offsets(bounds: Sequence[Bounds], gap: float = SIDE_GAP) -> list[float]:
    """x shift (m) of each run's arena in the side-by-side layout: each starts ``gap`` m right of the one
    before it (run A stays where it is)."""
    out = [0.0]
    right = bounds[0][1]
    for b in bounds[1:]:
        x0, x1 = b[0], b[1]
        shift = right + gap - x0
        out.append(shift)
        right = x1 + shift
    return out


def row_bounds(bounds: Sequence[Bounds], shifts: Sequence[float]) -> Bounds:
    """The rectangle (m) holding every run's arena moved by its shift."""
    return Bounds(min(b[0] + s for b, s in zip(bounds, shifts)), max(b[1] + s for b, s in zip(bounds, shifts)),
                  min(b[2] for b in bounds), max(b[3] for b in bounds))


def _yaw_wxyz(theta: NDArray[np.float64]) -> NDArray[np.float32]:
    h = 0.5 * theta
    z = np.zeros_like(h)
    return np.column_stack((np.cos(h), z, z, np.sin(h))).astype(np.float32)


class GhostRobots:
    """One run's robots drawn translucent in the run's colour (one batched mesh whatever N).

    Args:
        scene: the viser scene.
        name: the node's name (``/ghosts/B``).
        color: RGB 0–255.
        robot_radius: m.
    """

    def __init__(self, scene: viser.SceneApi, name: str, color: tuple[int, int, int],
                 robot_radius: float = ROBOT_RADIUS) -> None:
        self.scene = scene
        self.name = name
        self.color = color
        self.robot_radius = robot_radius
        self.node: viser.BatchedMeshHandle | None = None
        self._n = -1
        self.visible = True

    def draw(self, frame: Frame) -> None:
        """Put the ghosts at ``frame``'s poses (the mesh is remade when N changes)."""
        from swarmdeck.console.web.scene import robot_mesh

        pos = np.column_stack((frame.poses[:, :2], np.full(frame.n, 0.012))).astype(np.float32)
        wxyz = _yaw_wxyz(frame.poses[:, 2])
        if self.node is None or frame.n != self._n:
            if self.node is not None:
                self.node.remove()
            verts, faces = robot_mesh(self.robot_radius)
            self.node = self.scene.add_batched_meshes_simple(
                self.name, verts, faces, batched_wxyzs=wxyz, batched_positions=pos, batched_colors=self.color,
                opacity=GHOST_OPACITY, flat_shading=True, cast_shadow=False, receive_shadow=False,
                visible=self.visible)
            self._n = frame.n
            return
        self.node.batched_positions = pos
        self.node.batched_wxyzs = wxyz

    def set_visible(self, on: bool) -> None:
        self.visible = bool(on)
        if self.node is not None:
            self.node.visible = self.visible


def merge_series(histories: Sequence[PlotHistory], key: str) -> tuple[NDArray[np.float64], list[NDArray[np.float64]]]:
    """The runs' series ``key`` (:data:`~swarmdeck.console.web.plots.SERIES`) on one x axis: x (M,) the sorted
    union of every run's sample times (timeline s), and per run (M,) its last value at or before each x (NaN
    before its first and after its last sample)."""
    arrays = [h.arrays() for h in histories]
    times = [a["t"] for a in arrays]
    x = np.unique(np.concatenate(times)) if any(len(t) for t in times) else np.zeros(0)
    out: list[NDArray[np.float64]] = []
    for a in arrays:
        t, v = a["t"], a[key]
        if not len(t):
            out.append(np.full(len(x), math.nan))
            continue
        order = np.argsort(t, kind="stable")
        t, v = t[order], v[order]
        k = np.searchsorted(t, x, side="right") - 1
        y = v[np.clip(k, 0, None)].astype(float)
        y[(k < 0) | (x > t[-1])] = math.nan
        out.append(y)
    return x, out


COMPARE_CHARTS: tuple[tuple[str, str, str], ...] = (
    ("dmin", "Minimum distance (m)", "min distance"),
    ("active", "Active barrier constraints", "active"),
    ("H", "Coverage cost H(t)", "H"),
)
"""The compared charts: (series key, title, legend label)."""


class ComparePlots:
    """The "Plots" folder of a multi-run player: one chart per :data:`COMPARE_CHARTS` entry, one line per run.

    Args:
        gui: the viser GUI.
        names: the runs' names (A, B, …).
    """

    def __init__(self, gui: viser.GuiApi, names: Sequence[str]) -> None:
        colours = hex_colors(np.array([run_color(i) for i in range(len(names))], dtype=np.uint8))
        self.names = tuple(names)
        self.charts: dict[str, viser.GuiUplotHandle] = {}
        empty = tuple(np.zeros(1) for _ in range(len(names) + 1))
        with gui.add_folder("Plots"):
            for key, title, label in COMPARE_CHARTS:
                series = ({"label": "t (s, timeline)"},) + tuple(
                    {"label": f"{n} {label}", "stroke": c, "width": 2} for n, c in zip(names, colours))
                self.charts[key] = gui.add_uplot(empty, series, title=title, aspect=2.0,  # type: ignore[arg-type]
                                                 scales={"x": {"time": False}})

    def show(self, histories: Sequence[PlotHistory]) -> bool:
        """Draw the runs' histories (one per run, timeline times); False while every run has < 2 samples."""
        if all(len(h) < 2 for h in histories):
            return False
        for key, _title, _label in COMPARE_CHARTS:
            x, ys = merge_series(histories, key)
            self.charts[key].data = (x, *ys)
        return True
