"""swarmdeck.devices.fleet: keeping the arena's robots ready between experiments (paper §III-A, §III-C).

* :mod:`.chargers` — the charging strips along the walls and their docking slots (:class:`ChargerLayout`);
* :mod:`.battery` — the battery model: drain while driving, CC-CV charge while docked;
* :mod:`.assignment` — N charged, healthy robots mapped to experiment ids 0…N−1.
"""
from swarmdeck.devices.fleet.assignment import Assignment, AssignmentError, AssignmentPolicy, assign, eligibility
from swarmdeck.devices.fleet.battery import (
    BatteryParams,
    battery_step,
    charge_from_voltage,
    discharge,
    drain_current,
    recharge,
)
from swarmdeck.devices.fleet.chargers import WALLS, ChargerLayout

__all__ = [
    "Assignment", "AssignmentError", "AssignmentPolicy", "BatteryParams", "ChargerLayout", "WALLS", "assign",
    "battery_step", "charge_from_voltage", "discharge", "drain_current", "eligibility", "recharge",
]
