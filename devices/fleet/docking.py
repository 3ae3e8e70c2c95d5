"""Returning robots to free charger slots (paper §III-C "Charging": robots back onto the strips).

:func:`choose_slots` gives each returning robot a free slot (the least total distance to the
slots' approach poses, a linear assignment); :func:`return_maneuver` builds the maneuver that
docks them: the setup from the slots to the robots' poses played backwards
(:mod:`~swarmdeck.devices.fleet.retrace`; a full arena docks every robot), or, when that plan
cannot be made, :func:`staged_return_maneuver` — the
:class:`~swarmdeck.devices.fleet.maneuver.Maneuver` that drives each robot to its slot's
approach pose and then reverses it straight onto the strip, under the same barrier and deadlock
escape as the setup (robots nearer their slot go first). :meth:`ChargerLayout.docked_slot` says which
robots sit on a slot.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.constants import CONTROL_PERIOD, SAFETY_DISTANCE
from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.devices.chargers import ChargerLayout
from swarmdeck.devices.fleet.maneuver import Maneuver, ManeuverParams
from swarmdeck.devices.fleet.retrace import RetraceManeuver, plan_retrace
from swarmdeck.devices.fleet.setup import SetupFailed

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


def choose_slots(positions: ArrayLike, free: ArrayLike, layout: ChargerLayout) -> IntArray:
    """``(K,)`` slot index for each of K robots at ``positions`` ``(K, 2)`` m, among the ``free`` slots:
    the least total distance to the slots' approach poses, corner slots (:meth:`ChargerLayout.dock_blocks`)
    only when the others are taken.

    Raises:
        ValueError: fewer free reachable slots than robots (the message says how many of each).
    """
    from scipy.optimize import linear_sum_assignment

    p = np.asarray(positions, dtype=float).reshape(-1, 2)
    slots = np.asarray(free, dtype=np.intp).reshape(-1)
    occupied = np.setdiff1d(np.arange(layout.n_slots), slots)
    if len(occupied):  # a free slot whose way in a docked robot blocks cannot be reached
        slots = slots[~layout.dock_blocks()[np.ix_(occupied, slots)].any(axis=0)]
    if len(slots) < len(p):
        raise ValueError(f"{len(p)} robots must return but only {len(slots)} charger slots are free and reachable "
                         f"(the layout has {layout.n_slots})")
    app = layout.approach_poses()[slots, :2]
    blocks = layout.dock_blocks() | layout.approaches_clash()
    corner = np.any(blocks, axis=0)[slots] | np.any(blocks, axis=1)[slots]
    # corner slots (docked in a set order) only when the others are taken: 2 m more cost each
    cost = np.hypot(*(p[:, None, :] - app[None, :, :]).transpose(2, 0, 1)) + 2.0 * corner[None, :]
    r, c = linear_sum_assignment(cost)
    out = np.empty(len(p), dtype=np.intp)
    out[r] = slots[c]
    return out


def return_maneuver(poses: ArrayLike, slots: ArrayLike, layout: ChargerLayout,
                    robot: GritsBotParams = GritsBotParams(), params: ManeuverParams = ManeuverParams(),
                    hold_distance: float = 0.4, max_active: int | None = None, *,
                    occupied: ArrayLike | None = None, retrace: bool = True, safety_distance: float = SAFETY_DISTANCE,
                    gamma: float = 20.0, dt: float = CONTROL_PERIOD) -> Maneuver:
    """The maneuver that docks robots at ``poses`` ``(K, 3)`` on ``slots`` ``(K,)``.

    By default (``retrace``) the setup from ``slots`` to ``poses`` is planned under the fleet's
    barrier (``safety_distance``, linear κ with ``gamma``, period ``dt``; ``occupied``: slots whose
    robots stay docked, default :func:`~swarmdeck.devices.fleet.retrace.phantom_slots`) and played
    backwards (:class:`~swarmdeck.devices.fleet.retrace.RetraceManeuver`): a full arena docks every
    robot. When that plan does not finish, or with ``retrace=False``, the staged maneuver below.
    """
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    slots = np.asarray(slots, dtype=np.intp).reshape(-1)
    if retrace and len(p):
        try:
            plan = plan_retrace(p, slots, layout, robot, params, occupied=occupied, safety_distance=safety_distance,
                                gamma=gamma, dt=dt)
        except SetupFailed:
            pass  # the staged maneuver below
        else:
            return RetraceManeuver(plan, slots, layout, robot, params)
    return staged_return_maneuver(p, slots, layout, robot, params, hold_distance, max_active)


def staged_return_maneuver(poses: ArrayLike, slots: ArrayLike, layout: ChargerLayout,
                           robot: GritsBotParams = GritsBotParams(), params: ManeuverParams = ManeuverParams(),
                           hold_distance: float = 0.4, max_active: int | None = None) -> Maneuver:
    """Docking robots at ``poses`` ``(K, 3)`` on ``slots`` ``(K,)`` directly: approach, then reverse
    (reliable up to about 30 robots; a full arena jams — :func:`return_maneuver` retraces a plan instead).

    Priorities: the robot nearest its approach pose goes first (it is soonest out of the way). At a
    corner, a robot whose docked body would block another's way in (:meth:`ChargerLayout.dock_blocks`),
    or whose approach pose clashes with a higher-priority robot's (:meth:`ChargerLayout.approaches_clash`),
    waits ``hold_distance`` m from its approach pose towards the middle of the arena until the other has docked.
    At most ``max_active`` robots travel at once (the nearest first; the others stand where the
    experiment left them), so the band along the walls does not crowd; default: all up to 30
    robots, 20 above (measured: 30 robots return fastest all at once, 40 jam).
    """
    p = np.asarray(poses, dtype=float).reshape(-1, 3)
    slots = np.asarray(slots, dtype=np.intp).reshape(-1)
    k = len(p)
    docks, app = layout.dock_poses()[slots], layout.approach_poses()[slots]
    dist = np.hypot(*(p[:, :2] - app[:, :2]).T)
    # a slot whose docked robot blocks another's way in goes after it (level: longest such chain)
    blocks_all = layout.dock_blocks(robot.lookahead)
    level = np.zeros(layout.n_slots)
    for _ in range(layout.n_slots):  # converges within the longest chain (1 on the default layout)
        new = np.maximum(level, np.max(np.where(blocks_all, level[None, :] + 1, 0), axis=1))
        if np.array_equal(new, level):
            break
        level = new
    # one total order, so waiting never goes round in a circle: lower level first, then the nearest
    priority = np.empty(k)
    priority[np.lexsort((np.arange(k), dist, level[slots]))] = np.arange(k, 0, -1)
    # robot a waits while robot b, which goes first, still has to dock on a slot that a's docked
    # robot would block or whose approach pose clashes with a's
    conflict = (blocks_all | blocks_all.T | layout.approaches_clash())[np.ix_(slots, slots)]
    blocks = conflict & (priority[:, None] < priority[None, :])
    # waiting robots stand back towards the middle of the arena, clear of the other slots' approaches
    towards = np.array(layout.bounds.centre) - app[:, :2]
    hold = app.copy()
    hold[:, :2] += hold_distance * towards / np.maximum(np.hypot(towards[:, 0], towards[:, 1]), 1e-9)[:, None]
    if max_active is None and k > 30:
        max_active = 20
    return Maneuver(docks, layout.bounds, robot, params, priority=priority, reverse=np.ones(k, dtype=bool),
                    approach=app, wait_for=np.argwhere(blocks), hold=hold, max_active=max_active)

