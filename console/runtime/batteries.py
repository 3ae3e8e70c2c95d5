"""The robots' batteries as the console shows them: state of charge, level, low-battery warning.

Each Frame carries ``battery`` ``(N,)`` V (NaN: unknown, e.g. simulated or virtual robots, a robot
that has not reported yet) and ``charging`` ``(N,)`` (REFERENCE.md §9 ``batt_volt`` /
``charge_status``). The state of charge is the inverse of the battery model's voltage curve
(:func:`swarmdeck.devices.fleet.battery.charge_from_voltage`). The scene's bar, the Batteries
panel and the loop's "battery" alert all read it through :func:`battery_levels`, so they agree.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.checks import require_in_range
from swarmdeck.devices.fleet.battery import BatteryParams, charge_from_voltage

#: level names, lowest first (see :func:`battery_levels`)
LEVELS = ("unknown", "low", "fair", "good", "charging")
UNKNOWN, LOW, FAIR, GOOD, CHARGING = range(5)


@dataclass(frozen=True)
class BatteryWatch:
    """When the console warns.

    Attributes:
        warn_below: a robot off the charger below this state of charge ∈ [0, 1] raises the
            "battery low" alert (0.25: a quarter of the capacity left).
        fair_below: below this the bar is amber instead of green.
        params: the battery model whose voltage curve maps V to charge.
    """

    warn_below: float = 0.25
    fair_below: float = 0.5
    params: BatteryParams = field(default_factory=BatteryParams)

    def __post_init__(self) -> None:
        require_in_range(self.warn_below, "BatteryWatch.warn_below", 0.0, 1.0)
        require_in_range(self.fair_below, "BatteryWatch.fair_below", self.warn_below, 1.0)


def battery_levels(volts: NDArray[np.float64], charging: NDArray[np.bool_],
                   watch: BatteryWatch = BatteryWatch()) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """State of charge ``(N,)`` ∈ [0, 1] (NaN: unknown) and level ``(N,)`` (indices into :data:`LEVELS`:
    charging wins, then low < ``warn_below`` ≤ fair < ``fair_below`` ≤ good) of voltages ``(N,)`` V."""
    q = charge_from_voltage(np.asarray(volts, dtype=float), watch.params)
    level = np.select([np.isnan(q), q < watch.warn_below, q < watch.fair_below], [UNKNOWN, LOW, FAIR], GOOD)
    level = np.where(np.asarray(charging, dtype=bool), CHARGING, level)
    return q, level.astype(np.intp)


def low_battery_alert(ids: NDArray[np.int64], volts: NDArray[np.float64], charging: NDArray[np.bool_],
                      watch: BatteryWatch = BatteryWatch()) -> str | None:
    """``"battery low (< 25 %): robot(s) 3, 5"`` for the robots off the charger below ``warn_below``,
    or None. The text changes only when the set of robots does (it is an alert, logged when it
    changes; voltages are in the Batteries panel). Robots whose battery is unknown are not warned
    about here (the panel lists them)."""
    _, level = battery_levels(volts, charging, watch)
    low = np.asarray(ids)[level == LOW]
    if not len(low):
        return None
    return (f"battery low (< {watch.warn_below:.0%}): robot(s) {', '.join(str(int(i)) for i in low)}; "
            "return them to the chargers")
