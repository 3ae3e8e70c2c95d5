"""Per-step validation of a run, counted the way the Robotarium's rps simulator does.

REFERENCE.md §1–2: a robot is out of bounds when its centre leaves the arena
rectangle; two robots collide when their centres, each shifted 0.025 m forward
along its heading, are at most 0.135 m apart; an actuator error is a command
whose wheel speeds exceed the limit. swarmdeck counts each per robot *and* per
step, and keeps the acceptance rules of the Robotarium's verifier. A robot touches a
line-segment obstacle (:mod:`swarmdeck.core.obstacles`) when its shifted centre is at most
half the collision distance from the segment (the same body as in the pair test); obstacle
contacts are counted like collisions and the verifier's rule applies to them too.
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.bounds import Bounds
from swarmdeck.core.constants import COLLISION_DISTANCE, COLLISION_SHIFT
from swarmdeck.core.kinematics import lookahead_points
from swarmdeck.core.obstacles import Obstacles, segments_near


@dataclass(frozen=True)
class ValidationRules:
    """Thresholds of the rps validator and the Robotarium verifier (REFERENCE.md §1–2).

    Attributes:
        collision_shift: forward shift of each centre before the distance test, m.
        collision_distance: shifted centres at most this far apart collide, m.
        max_violation_steps: the verifier rejects a run with more steps than this
            with robots too close, or with robots out of bounds.
        max_time_factor: the verifier rejects runs longer than this × declared duration.
    """

    collision_shift: float = COLLISION_SHIFT
    collision_distance: float = COLLISION_DISTANCE
    max_violation_steps: int = 100
    max_time_factor: float = 1.5


def out_of_bounds(poses: ArrayLike, bounds: Bounds) -> NDArray[np.bool_]:
    """``(N,)`` mask of robots whose centre lies outside the rectangle ``bounds``."""
    p = np.asarray(poses, dtype=float)
    x0, x1, y0, y1 = bounds
    return (p[:, 0] < x0) | (p[:, 0] > x1) | (p[:, 1] < y0) | (p[:, 1] > y1)


ALL_PAIRS_MAX = 64  # robots up to which colliding_pairs tests all pairs (rps allows 50)


@functools.lru_cache(maxsize=ALL_PAIRS_MAX)
def _upper_pairs(n: int) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """``np.triu_indices(n, 1)``, read-only and kept (building it costs more than testing the pairs)."""
    i, j = np.triu_indices(n, 1)
    i.setflags(write=False)
    j.setflags(write=False)
    return i, j


def colliding_pairs(poses: ArrayLike, rules: ValidationRules = ValidationRules()) -> NDArray[np.intp]:
    """``(K, 2)`` index pairs ``i < j`` that collide by the rps test, in lexicographic order.

    Up to ``ALL_PAIRS_MAX`` robots every pair is tested at once in numpy (at most 2016 pairs: faster there
    than building a k-d tree, and no scipy import); beyond, a k-d tree finds the candidates."""
    p = np.asarray(poses, dtype=float)
    n = p.shape[0]
    if n < 2:
        return np.empty((0, 2), dtype=np.intp)
    if n <= ALL_PAIRS_MAX:  # rps shifts each centre ahead along its heading
        x = p[:, 0] + rules.collision_shift * np.cos(p[:, 2])
        y = p[:, 1] + rules.collision_shift * np.sin(p[:, 2])
        i, j = _upper_pairs(n)  # lexicographic
        close = np.hypot(x[i] - x[j], y[i] - y[j]) <= rules.collision_distance  # (no overflow in a square)
        if not close.any():  # the usual step: no pair (the same empty (0, 2) intp answer)
            return np.empty((0, 2), dtype=np.intp)
        return np.column_stack((i[close], j[close]))
    shifted = lookahead_points(p, rules.collision_shift)
    from scipy.spatial import cKDTree  # here, not at import: a sandboxed script's process never needs scipy

    # Chebyshev candidates, then the exact distance by hypot: the Euclidean k-d tree squares
    # coordinates and raises for finite positions beyond ~1e154 m
    cand = cKDTree(shifted).query_pairs(rules.collision_distance, p=np.inf, output_type="ndarray")
    e = shifted[cand[:, 0]] - shifted[cand[:, 1]]
    close = np.hypot(e[:, 0], e[:, 1]) <= rules.collision_distance
    return cand[close][np.lexsort((cand[close][:, 1], cand[close][:, 0]))].astype(np.intp)


def obstacle_contacts(poses: ArrayLike, obstacles: Obstacles, rules: ValidationRules = ValidationRules()
                      ) -> NDArray[np.bool_]:
    """``(N,)`` robots whose body — the centre shifted ``collision_shift`` forward, radius
    ``collision_distance / 2`` (the pair test's body) — touches a segment of ``obstacles``."""
    p = np.asarray(poses, dtype=float)
    out = np.zeros(p.shape[0], dtype=bool)
    if obstacles.m == 0 or p.shape[0] == 0:
        return out
    i, _, _ = segments_near(lookahead_points(p, rules.collision_shift), obstacles.segments,
                            rules.collision_distance / 2)
    out[i] = True
    return out


@dataclass
class ValidationReport:
    """Running counts of a run: per robot (arrays of length N) and per step.

    ``steps_with_*`` count steps in which at least one robot had that error;
    ``*_per_robot`` count, for each robot, the steps in which it had it.
    """

    n_robots: int
    steps: int = 0
    time: float = 0.0
    collisions_per_robot: NDArray[np.int64] = field(default=None)  # type: ignore[arg-type]
    boundary_per_robot: NDArray[np.int64] = field(default=None)  # type: ignore[arg-type]
    actuator_per_robot: NDArray[np.int64] = field(default=None)  # type: ignore[arg-type]
    invalid_command_per_robot: NDArray[np.int64] = field(default=None)  # type: ignore[arg-type]
    steps_with_collision: int = 0
    steps_with_boundary: int = 0
    steps_with_actuator: int = 0
    collision_pairs: int = 0
    first_collision_time: float | None = None
    obstacle_contacts_per_robot: NDArray[np.int64] = field(default=None)  # type: ignore[arg-type]
    steps_with_obstacle_contact: int = 0
    first_obstacle_contact_time: float | None = None

    def __post_init__(self) -> None:
        for name in ("collisions_per_robot", "boundary_per_robot", "actuator_per_robot", "invalid_command_per_robot",
                     "obstacle_contacts_per_robot"):
            if getattr(self, name) is None:
                setattr(self, name, np.zeros(self.n_robots, dtype=np.int64))

    def record(
        self,
        poses: ArrayLike,
        bounds: Bounds,
        saturated: NDArray[np.bool_],
        invalid: NDArray[np.bool_],
        time: float,
        rules: ValidationRules = ValidationRules(),
        obstacles: Obstacles | None = None,
    ) -> NDArray[np.intp]:
        """Count one step's errors at the post-step ``poses``; returns the colliding pairs.
        ``obstacles``: the run's line segments, whose contacts (:func:`obstacle_contacts`) are counted."""
        pairs = colliding_pairs(poses, rules)
        if obstacles is not None and obstacles.m:
            touch = obstacle_contacts(poses, obstacles, rules)
            if touch.any():
                self.obstacle_contacts_per_robot += touch
                self.steps_with_obstacle_contact += 1
                if self.first_obstacle_contact_time is None:
                    self.first_obstacle_contact_time = time
        oob = out_of_bounds(poses, bounds)
        self.steps += 1
        self.time = time
        if len(pairs):
            hit = np.zeros(self.n_robots, dtype=bool)
            hit[pairs.ravel()] = True
            self.collisions_per_robot += hit
            self.steps_with_collision += 1
            self.collision_pairs += len(pairs)
            if self.first_collision_time is None:
                self.first_collision_time = time
        if oob.any():  # (a mask without a robot adds nothing)
            self.boundary_per_robot += oob
            self.steps_with_boundary += 1
        if np.any(saturated):
            self.actuator_per_robot += saturated
            self.steps_with_actuator += 1
        if np.any(invalid):
            self.invalid_command_per_robot += invalid
        return pairs

    def verdict(self, declared_duration: float | None = None, rules: ValidationRules = ValidationRules()) -> list[str]:
        """Reasons the Robotarium verifier would reject this run (empty when accepted)."""
        reasons = []
        if self.steps_with_collision > rules.max_violation_steps:
            reasons.append(f"robots too close in {self.steps_with_collision} steps (> {rules.max_violation_steps})")
        if self.steps_with_obstacle_contact > rules.max_violation_steps:
            reasons.append(f"robots touching obstacles in {self.steps_with_obstacle_contact} steps "
                           f"(> {rules.max_violation_steps})")
        if self.steps_with_boundary > rules.max_violation_steps:
            reasons.append(f"robots out of bounds in {self.steps_with_boundary} steps (> {rules.max_violation_steps})")
        if declared_duration is not None and self.time > rules.max_time_factor * declared_duration:
            reasons.append(
                f"simulated time {self.time:.1f} s exceeds {rules.max_time_factor} x declared {declared_duration:.1f} s"
            )
        return reasons

    def to_dict(self) -> dict:
        """A JSON-serialisable summary."""
        return {
            "n_robots": self.n_robots,
            "steps": self.steps,
            "time": self.time,
            "steps_with_collision": self.steps_with_collision,
            "steps_with_boundary": self.steps_with_boundary,
            "steps_with_actuator": self.steps_with_actuator,
            "collision_pairs": self.collision_pairs,
            "first_collision_time": self.first_collision_time,
            "collisions_per_robot": self.collisions_per_robot.tolist(),
            "boundary_per_robot": self.boundary_per_robot.tolist(),
            "actuator_per_robot": self.actuator_per_robot.tolist(),
            "invalid_command_per_robot": self.invalid_command_per_robot.tolist(),
            **({"steps_with_obstacle_contact": self.steps_with_obstacle_contact,
                "first_obstacle_contact_time": self.first_obstacle_contact_time,
                "obstacle_contacts_per_robot": self.obstacle_contacts_per_robot.tolist()}
               if self.steps_with_obstacle_contact else {}),
        }

    def summary(self, invalid_upstream: int = 0, saturated_upstream: tuple[int, int] = (0, 0)) -> str:
        """Human-readable lines, as rps's ``call_at_scripts_end`` prints.

        ``invalid_upstream``: robot-steps whose non-finite command was already stopped
        before reaching the robots (by :class:`~swarmdeck.devices.Arena`), added to the count.
        ``saturated_upstream``: (robot-steps, steps) whose commands were already scaled down to
        the wheel limits before reaching the robots, shown with the robots' own count.
        """
        lines = [
            f"robots: {self.n_robots}   steps: {self.steps}   simulated time: {self.time:.2f} s",
            f"collisions: {self.collision_pairs} pair-steps in {self.steps_with_collision} steps"
            + (f" (first at {self.first_collision_time:.2f} s)" if self.first_collision_time is not None else ""),
            f"out of bounds: {int(self.boundary_per_robot.sum())} robot-steps in {self.steps_with_boundary} steps",
            f"actuator saturation: {int(self.actuator_per_robot.sum())} robot-steps in {self.steps_with_actuator} steps"
            + (f" at the robots; commands scaled down to the wheel limits: {saturated_upstream[0]} robot-steps in "
               f"{saturated_upstream[1]} steps" if saturated_upstream[0] else ""),
            f"invalid (NaN/inf) commands stopped: {int(self.invalid_command_per_robot.sum()) + int(invalid_upstream)} robot-steps",
        ]
        if self.steps_with_obstacle_contact:
            lines.insert(2, f"obstacle contacts: {int(self.obstacle_contacts_per_robot.sum())} robot-steps in "
                            f"{self.steps_with_obstacle_contact} steps (first at {self.first_obstacle_contact_time:.2f} s)")
        return "\n".join(lines)
