"""The Batteries panel: one row per robot — battery voltage, state of charge, charging, virtual.

Drawn from Frames (``battery``, ``charging``, ``is_virtual``; :mod:`swarmdeck.console.runtime.batteries`
for the levels), so the live console and playback show the same table. Robots below the warning
threshold are listed first, under a ⚠ line; robots whose battery is unknown say so (simulated and
virtual robots have none).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from swarmdeck.console.runtime.batteries import CHARGING, LEVELS, LOW, BatteryWatch, battery_levels
from swarmdeck.console.runtime.frame import Frame, filled

if TYPE_CHECKING:
    import viser

_MARK = {"unknown": "–", "low": "🔴 low", "fair": "🟠", "good": "🟢", "charging": "🔵 charging"}


def battery_table(frame: Frame, watch: BatteryWatch = BatteryWatch(), max_rows: int = 60) -> str:
    """The panel's markdown: a ⚠ line naming the robots low on battery, then a table (low robots
    first, then by id; at most ``max_rows`` rows, the rest counted)."""
    n = frame.n
    if n == 0:
        return "no robots"
    battery, is_virtual = filled(frame.battery), filled(frame.is_virtual)
    q, level = battery_levels(battery, filled(frame.charging), watch)
    known = ~np.isnan(q)
    if not known.any():
        return "no battery reports (simulated robots have none; `--robots-via` robots report theirs)"
    ids = frame.ids
    low = ids[level == LOW]
    lines = []
    if len(low):
        lines.append(f"⚠ **battery low** (< {watch.warn_below:.0%}): robot(s) {', '.join(str(int(i)) for i in low)}")
    lines.append(f"{int(known.sum())}/{n} report · {int((level == CHARGING).sum())} charging · "
                 f"lowest {np.nanmin(q):.0%}")
    lines += ["", "| robot | V | charge | state |", "|---:|---:|---:|:---|"]
    order = np.lexsort((ids, level != LOW))
    for k in order[:max_rows]:  # the panel's table (≤ max_rows rows, refreshed a few times a second)
        name = f"{int(ids[k])}" + (" (virtual)" if is_virtual[k] else "")
        volts = f"{battery[k]:.2f}" if known[k] else "–"
        charge = f"{q[k]:.0%}" if known[k] else "–"
        lines.append(f"| {name} | {volts} | {charge} | {_MARK[LEVELS[level[k]]]} |")
    if n > max_rows:
        lines.append(f"… and {n - max_rows} more")
    return "\n".join(lines)


class BatteryPanel:
    """A "Batteries" folder on a viser GUI showing :func:`battery_table` of the Frames it is given."""

    def __init__(self, gui: viser.GuiApi, watch: BatteryWatch = BatteryWatch()) -> None:
        self.watch = watch
        with gui.add_folder("Batteries", expand_by_default=True):
            self.table = gui.add_markdown("no robots yet")

    def show(self, frame: Frame) -> None:
        text = battery_table(frame, self.watch)
        if text != self.table.content:
            self.table.content = text
