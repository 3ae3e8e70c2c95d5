"""swarmdeck.devices.fleet: keeping the arena's robots ready between experiments (paper §III-A, §III-C).

* :mod:`.chargers` — the charging strips along the walls and their docking slots (:class:`ChargerLayout`);
* :mod:`.battery` — the battery model: drain while driving, CC-CV charge while docked;
* :mod:`.assignment` — N charged, healthy robots mapped to experiment ids 0…N−1;
* :mod:`.maneuver` — nominal commands to goal poses with the deadlock escape (setup and return);
* :mod:`.setup` — start-pose checks and driving a maneuver under the barrier (:func:`drive`);
* :mod:`.docking` — free charger slots for returning robots and the docking maneuver;
* :mod:`.retrace` — the return as the setup played backwards (a full arena docks every robot);
* :mod:`.manager` — :class:`FleetManager`, the fleet between experiments over a simulated arena.
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
from swarmdeck.devices.fleet.docking import choose_slots, return_maneuver
from swarmdeck.devices.fleet.manager import FleetConfig, FleetExperiment, FleetManager
from swarmdeck.devices.fleet.maneuver import Maneuver, ManeuverParams
from swarmdeck.devices.fleet.setup import ManeuverReport, SetupFailed, check_start_poses, drive

__all__ = [
    "Assignment", "AssignmentError", "AssignmentPolicy", "BatteryParams", "ChargerLayout", "WALLS", "assign",
    "battery_step", "charge_from_voltage", "discharge", "drain_current", "eligibility", "recharge",
    "FleetConfig", "FleetExperiment", "FleetManager", "Maneuver", "ManeuverParams", "ManeuverReport", "SetupFailed",
    "check_start_poses", "choose_slots", "drive", "return_maneuver",
]
