"""swarmdeck.devices.fleet: keeping the arena's robots ready between experiments (paper §III-A, §III-C).

* the charging strips (:class:`~swarmdeck.devices.chargers.ChargerLayout`) and the battery model
  (:mod:`swarmdeck.devices.battery`) are the arena's hardware, in the devices root (re-exported here);
* :mod:`.assignment` — N charged, healthy robots mapped to experiment ids 0…N−1;
* :mod:`.assigned` — :class:`AssignedRobots`, those robots as an experiment's robot ports 0…N−1;
* :mod:`.maneuver` — nominal commands to goal poses with the deadlock escape (setup and return);
* :mod:`.task` — :class:`UpkeepTask`, one setup or return: maneuver, robots, time limit, lost-robot
  rule, progress and failure messages (driven by :func:`drive` and by the console loop's ``FleetManeuver``);
* :mod:`.setup` — start-pose checks and driving a task over a simulated fleet's ports (:func:`drive`);
* :mod:`.docking` — free charger slots for returning robots and the docking maneuver;
* :mod:`.retrace` — the return as the setup played backwards (a full arena docks every robot);
* :mod:`.manager` — :class:`FleetManager`, the fleet between experiments over a simulated arena.
"""
from swarmdeck.devices.battery import (
    BatteryParams,
    battery_step,
    charge_from_voltage,
    discharge,
    drain_current,
    recharge,
)
from swarmdeck.devices.chargers import WALLS, ChargerLayout
from swarmdeck.devices.fleet.assigned import AssignedRobots
from swarmdeck.devices.fleet.assignment import Assignment, AssignmentError, AssignmentPolicy, assign, eligibility
from swarmdeck.devices.fleet.docking import choose_slots, return_maneuver
from swarmdeck.devices.fleet.manager import FleetConfig, FleetManager
from swarmdeck.devices.fleet.maneuver import Maneuver, ManeuverParams
from swarmdeck.devices.fleet.setup import ManeuverReport, SetupFailed, check_start_poses, drive
from swarmdeck.devices.fleet.task import UpkeepTask

__all__ = [
    "Assignment", "AssignmentError", "AssignmentPolicy", "BatteryParams", "ChargerLayout", "WALLS", "assign",
    "battery_step", "charge_from_voltage", "discharge", "drain_current", "eligibility", "recharge",
    "AssignedRobots", "FleetConfig", "FleetManager", "Maneuver", "ManeuverParams", "ManeuverReport", "SetupFailed",
    "UpkeepTask", "check_start_poses", "choose_slots", "drive", "return_maneuver",
]
