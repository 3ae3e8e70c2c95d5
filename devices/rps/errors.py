"""rps's error bookkeeping (``Robotarium._errors``) and its end-of-script texts, for both rps generations.

rps validates at the start of every ``step()`` — the poses the script saw and the velocities it set, before
thresholding — and counts into ``_errors`` (robotarium/robotarium_python_simulator):

* 1.x (``dev`` branch, ``robotarium_abc._validate``): ``"boundary"`` {robot: steps outside the arena},
  ``"collision"`` {robot: colliding pairs it was in}, ``"actuator"``: steps in which some wheel exceeded
  its limit, each with its ``*_string``; printed by ``call_at_scripts_end()``.
* 2.0 (``master``): ``"robots_outside_boundaries"`` (steps), ``"robots_too_close"`` (colliding pairs,
  summed over steps), ``"exceeded_actuator_limits"`` (steps); printed by ``debug()``.

The facade keeps both sets of keys in one dict (a script of either generation finds its own). Collisions:
centres shifted 0.025 m ahead along the heading, at most 0.135 m apart (REFERENCE.md §1,
:class:`~swarmdeck.devices.validation.ValidationRules`), vectorised, not rps's pairwise loops. Unlike rps 1.x,
no mutable default dict is shared between Robotarium objects.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.bounds import Bounds
from swarmdeck.devices.validation import colliding_pairs, out_of_bounds

BOUNDARY_STRING = "iteration(s) robots were outside the boundaries."
COLLISION_STRING = "iteration(s) where robots collided."
ACTUATOR_STRING = ("iteration(s) where the actuator limits of at least one robot were exceeded and thresholded to "
                   "their maximum rotational velocity.")


def count_errors(errors: dict[str, Any], poses: NDArray[np.float64], wheels_over: bool,
                 bounds: Bounds, pairs: NDArray[np.intp] | None = None) -> None:
    """Add one step's errors to ``errors`` (rps's ``_errors``, updated in place: it is the facade's own).

    ``poses``: (N, 3) rows, the poses validated; ``wheels_over``: some wheel of the commanded velocities
    exceeds its limit; ``pairs``: the colliding pairs at ``poses`` when already known (else computed).
    """
    if pairs is None:
        pairs = colliding_pairs(poses)
    oob = out_of_bounds(poses, bounds)
    if oob.any():
        boundary = errors.setdefault("boundary", {})
        for i in np.flatnonzero(oob).tolist():
            boundary[i] = boundary.get(i, 0) + 1
        errors["boundary_string"] = BOUNDARY_STRING
        errors["robots_outside_boundaries"] = errors.get("robots_outside_boundaries", 0) + 1
    if len(pairs):
        collision = errors.setdefault("collision", {})
        robots, counts = np.unique(pairs.ravel(), return_counts=True)
        for i, c in zip(robots.tolist(), counts.tolist()):
            collision[i] = collision.get(i, 0) + c
        errors["collision_string"] = COLLISION_STRING
        errors["robots_too_close"] = errors.get("robots_too_close", 0) + len(pairs)
    if wheels_over:
        errors["actuator"] = errors.get("actuator", 0) + 1
        errors["actuator_string"] = ACTUATOR_STRING
        errors["exceeded_actuator_limits"] = errors.get("exceeded_actuator_limits", 0) + 1


def call_at_scripts_end_text(errors: dict[str, Any], iterations: int, time_step: float) -> str:
    """What rps 1.x's ``call_at_scripts_end()`` prints, line for line."""
    lines = ["##### DEBUG OUTPUT #####",
             f"Your simulation will take approximately {math.ceil(iterations * time_step)} real seconds when deployed on the Robotarium. \n"]
    if "boundary" in errors or "collision" in errors or "actuator" in errors:
        if "boundary" in errors:
            lines.append("\t Simulation had {0} {1}\n".format(max(errors["boundary"].values()), errors["boundary_string"]))
        if "collision" in errors:
            lines.append("\t Simulation had {0} {1}\n".format(max(errors["collision"].values()),
                                                              errors["collision_string"]))
        if "actuator" in errors:
            lines.append("\t Simulation had {0} {1}".format(errors["actuator"], errors["actuator_string"]))
    else:
        lines.append("No errors in your simulation! Acceptance of your experiment is likely!")
    return "\n".join(lines)


def debug_text(errors: dict[str, Any], iterations: int, time_step: float) -> str:
    """What rps 2.0's ``debug()`` prints, line for line."""
    lines = [f"Your simulation took approximately {iterations * time_step:.2f} real seconds to execute.\n"]
    too_close = errors.get("robots_too_close", 0)
    out_of_bounds_steps = errors.get("robots_outside_boundaries", 0)
    actuator = errors.get("exceeded_actuator_limits", 0)
    hard_errors = too_close + out_of_bounds_steps
    if hard_errors == 0 and actuator == 0:
        lines.append("No errors or warnings in your simulation!  Your script will run on the Robotarium!\n")
    elif hard_errors == 0:
        lines.append("No hard errors detected, your script will run on the Robotarium!\n")
        lines.append(f"WARNING: {actuator} out of {iterations} "
                     f"(~{100 * actuator / max(iterations, 1):.0f}%) timesteps had velocity "
                     f"command(s) exceed actuator limits.\n"
                     f"         A large percentage of exceeded actuator commands will cause noticeable\n"
                     f"         differences between this simulation and the physical Robotarium.")
    else:
        lines.append("Errors detected, your script will NOT run on the Robotarium!\n")
        lines.append("Errors:")
        if too_close:
            lines.append(f"\t Simulation had {too_close} time steps where robots were too close (potential collision).")
        if out_of_bounds_steps:
            lines.append(f"\t Simulation had {out_of_bounds_steps} time steps where robots were outside boundaries.")
        lines.append("\nPlease fix the noted errors in your simulation; otherwise, your experiment will be rejected.")
    return "\n".join(lines)
