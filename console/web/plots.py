"""The Plots panel: one drawing code for the live console and for playback (DESIGN.md "One tick").

:class:`PlotHistory` keeps the last :data:`PLOT_WINDOW` samples of the numbers
a Frame contributes (:func:`frame_sample`); :class:`PlotsPanel` draws a history
as four uPlot charts in a "Plots" folder of a viser GUI. The live console
(:class:`~swarmdeck.console.web.gui.ConsoleGui`) adds every Frame the loop
produces; the player (:class:`~swarmdeck.console.web.player.PlayerApp`) adds
the Frames it shows (and, after a seek, the seconds before the new position).
Live and playback therefore differ only in where Frames come from.

The charts, against session time t in s (since the session's first Frame: the
loop's ``time_origin`` live, the recording's first frame in playback — the
time base ``swarmdeck info`` and ``play`` use too):

* minimum pairwise distance of the look-ahead points (m) and the barrier's D_s (m);
* active barrier constraints;
* coverage cost H (left scale) and mean ‖p − c‖ (m, right scale);
* tick time and barrier solve time (ms).

A number a Frame does not carry (no barrier record, no coverage state, an
infinite minimum distance with fewer than two robots) is NaN: a gap in the
chart, never a made-up value.
"""
from __future__ import annotations

import math
import threading
from collections import deque
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.runtime.frame import Frame

if TYPE_CHECKING:
    import viser
    from viser import uplot

# One period of the console's circling bump (20 s) at the default 0.033 s control period.
PLOT_WINDOW = 600

SERIES: tuple[str, ...] = ("t", "dmin", "ds", "active", "H", "mpc", "tick_ms", "solve_ms")
"""Names of the sampled series: time (s), min distance (m), D_s (m), active constraints,
H, mean ‖p − c‖ (m), tick time (ms), barrier solve time (ms)."""

_NAN = math.nan
NO_COVERAGE = ("*H(t) and mean ‖p − c‖ are coverage quantities: no coverage state in the frames shown "
               "(another behaviour runs). Switch to coverage to plot them.*")


def _finite_or_nan(x: float) -> float:
    return float(x) if math.isfinite(x) else _NAN


def frame_sample(frame: Frame) -> tuple[float, ...]:
    """The plotted numbers of one Frame, in the order of ``SERIES[1:]`` (NaN where it has none)."""
    b, c = frame.barrier, frame.coverage
    total = frame.timing.get("total")
    return (
        _finite_or_nan(b.min_distance) if b is not None else _NAN,
        float(b.safety_distance) if b is not None else _NAN,
        float(b.n_active) if b is not None else _NAN,
        float(c.cost_H) if c is not None else _NAN,
        float(c.mean_centroid_distance) if c is not None else _NAN,
        1e3 * float(total) if total is not None else _NAN,
        1e3 * float(b.solve_time_s) if b is not None else _NAN,
    )


class PlotHistory:
    """The last ``window`` samples of :data:`SERIES` (thread-safe: one thread adds, another reads).

    Args:
        window: samples kept (the oldest are dropped).
    """

    def __init__(self, window: int = PLOT_WINDOW) -> None:
        if not (isinstance(window, int) and window >= 2):
            raise ValueError(f"plot window must be an integer >= 2 samples, got {window!r}")
        self.window = window
        self._lock = threading.Lock()
        self._rows: deque[tuple[float, ...]] = deque(maxlen=window)

    def add(self, t: float, frame: Frame) -> None:
        """Append the sample of ``frame`` at plot time ``t`` (s)."""
        row = (float(t),) + frame_sample(frame)
        with self._lock:
            self._rows.append(row)

    def clear(self) -> None:
        with self._lock:
            self._rows.clear()

    def __len__(self) -> int:
        return len(self._rows)

    @property
    def last_time(self) -> float | None:
        """Plot time of the newest sample, s (None when empty)."""
        with self._lock:
            return self._rows[-1][0] if self._rows else None

    def arrays(self) -> dict[str, NDArray[np.float64]]:
        """Each series as a float array (K,), oldest first."""
        with self._lock:
            table = np.array(self._rows, dtype=float).reshape(-1, len(SERIES))
        return {name: table[:, i] for i, name in enumerate(SERIES)}


CHARTS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("dist", ("t", "dmin", "ds")),
    ("active", ("t", "active")),
    ("H", ("t", "H", "mpc")),
    ("tick", ("t", "tick_ms", "solve_ms")),
)
"""Each chart's name and the series it shows (x first)."""


class PlotsPanel:
    """The four charts in a "Plots" folder of ``gui`` (a ``viser.GuiApi``); :meth:`show` draws a history."""

    def __init__(self, gui: viser.GuiApi, expand_by_default: bool = True) -> None:
        x: dict[str, uplot.Scale] = {"x": {"time": False}}
        with gui.add_folder("Plots", expand_by_default=expand_by_default):
            self.dist: viser.GuiUplotHandle = gui.add_uplot(
                (np.zeros(1), np.zeros(1), np.zeros(1)),
                ({"label": "t (s, session)"}, {"label": "min distance (m)", "stroke": "#1f77b4", "width": 2},
                 {"label": "D_s (m)", "stroke": "#d62728", "width": 1, "dash": (6.0, 4.0)}),
                title="Minimum distance vs D_s", aspect=2.0, scales=x)
            self.active: viser.GuiUplotHandle = gui.add_uplot(
                (np.zeros(1), np.zeros(1)),
                ({"label": "t (s, session)"}, {"label": "active constraints", "stroke": "#ff7f0e", "width": 2}),
                title="Active barrier constraints", aspect=2.5, scales=x)
            self.H: viser.GuiUplotHandle = gui.add_uplot(
                (np.zeros(1), np.zeros(1), np.zeros(1)),
                ({"label": "t (s, session)"}, {"label": "H", "stroke": "#2ca02c", "width": 2, "scale": "H"},
                 {"label": "mean ‖p−c‖ (m)", "stroke": "#9467bd", "width": 2, "scale": "m"}),
                title="Coverage cost H(t) and mean ‖p − c‖", aspect=2.0,
                scales={**x, "H": {"auto": True}, "m": {"auto": True}},
                axes=({}, {"scale": "H"}, {"scale": "m", "side": 1}))
            self.H_note: viser.GuiMarkdownHandle = gui.add_markdown(NO_COVERAGE, visible=False)
            self.tick: viser.GuiUplotHandle = gui.add_uplot(
                (np.zeros(1), np.zeros(1), np.zeros(1)),
                ({"label": "t (s, session)"}, {"label": "tick (ms)", "stroke": "#17becf", "width": 2},
                 {"label": "barrier solve (ms)", "stroke": "#8c564b", "width": 1}),
                title="Tick time", aspect=2.5, scales=x)

    def handles(self) -> dict[str, viser.GuiUplotHandle]:
        """The chart handles by name (``CHARTS``)."""
        return {"dist": self.dist, "active": self.active, "H": self.H, "tick": self.tick}

    def show(self, history: PlotHistory) -> bool:
        """Put ``history`` into the charts; False (charts unchanged) while it has fewer than 2 samples."""
        if len(history) < 2:
            return False
        s = history.arrays()
        handles = self.handles()
        for name, keys in CHARTS:
            handles[name].data = tuple(s[k] for k in keys)
        coverage = bool(np.isfinite(s["H"]).any())  # H is a coverage quantity: a note instead of a blank chart
        if self.H.visible != coverage:
            self.H.visible, self.H_note.visible = coverage, not coverage
        return True
