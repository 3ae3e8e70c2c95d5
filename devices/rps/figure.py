"""The rps figure, headless: ``Robotarium.figure``/``.axes`` and ``misc.plt`` for scripts that plot.

rps draws the arena in a matplotlib window and its plotting examples add goal markers,
captions and images to ``r.axes``. Under swarmdeck nothing is shown (watch runs in
``swarmdeck console`` or a recording); the figure is real but on matplotlib's non-interactive
Agg backend, so those calls work unchanged and cost little. What the script draws inside the arena
is drawn on the arena as the Robotarium 2.0 projects it (:mod:`.figure_annotations`; every ``step()``).
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Any

from swarmdeck.devices.rps.figure_annotations import SWARMDECK_GID

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the Agg backend (no window, no display needed)."""
    import matplotlib

    matplotlib.use("Agg")  # before pyplot is imported; a script's later plt.show() is then a no-op
    import matplotlib.pyplot as plt

    from swarmdeck.devices.rps import provide_get_cmap, quiet_canvas

    provide_get_cmap()  # rps-era scripts colour with plt.cm.get_cmap
    quiet_canvas()  # nothing shows the figure: its redraw requests cost nothing

    return plt


def arena_figure(boundaries: tuple[float, float, float, float]) -> tuple[Figure, Axes]:
    """A figure and axes showing the arena ``(x_min, y_min, width, height)`` in metres, as rps sets up."""
    plt = pyplot()
    from matplotlib.patches import Rectangle

    figure, axes = plt.subplots()
    x0, y0, w, h = boundaries
    axes.add_patch(Rectangle((x0, y0), w, h, fill=False, gid=SWARMDECK_GID))  # the arena, not the script's
    axes.set_xlim(x0 - 0.1, x0 + w + 0.1)
    axes.set_ylim(y0 - 0.1, y0 + h + 0.1)
    axes.set_aspect("equal")
    axes.set_axis_off()
    return figure, axes
