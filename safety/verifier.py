"""Simulation-based verification and the safety score (REFERENCE.md §4, paper §IV-A).

Robots are discs of diameter ``contact_distance`` around single-integrator
points moving linearly within each step. Collision detection is two-phase:

* broad phase: a k-d tree query for pairs whose swept discs can meet within
  the step (distance ≤ D + |Δx_i|max + |Δx_j|max);
* narrow phase: the exact time of first contact of two discs moving linearly,
  the smallest root in [0, dt] of ‖r₀ + t·v_r‖² = D² (a quadratic).

At a contact the involved robots stop at the contact instant for the rest of
the step (non-penetration) and the event is recorded with the commanded
approach speed along the contact normal. The score is

    S = 1 − Σ_contacts v_n / (N · steps · v_max),   clipped to [0, 1],

1 when collision-free and 0 for the worst case of every robot hitting at full
speed at every step.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from swarmdeck.core.constants import CONTROL_PERIOD, MAX_LINEAR_SPEED, ROBOT_DIAMETER


def first_contact_times(r0: np.ndarray, vr: np.ndarray, distance: float, dt: float) -> np.ndarray:
    """Earliest t ∈ [0, dt] with ‖r0 + t·vr‖ = distance for each relative pair (K, 2); inf if none.

    Pairs already closer than ``distance`` and still approaching give 0.
    """
    a = np.einsum("kd,kd->k", vr, vr)
    b = 2 * np.einsum("kd,kd->k", r0, vr)
    c = np.einsum("kd,kd->k", r0, r0) - distance**2
    t = np.full(r0.shape[0], np.inf)
    overlapping = (c <= 0) & (b < 0)
    t[overlapping] = 0.0
    disc = b * b - 4 * a * c
    moving = (c > 0) & (a > 0) & (disc >= 0) & (b < 0)
    root = (-b[moving] - np.sqrt(disc[moving])) / (2 * a[moving])
    t_m = np.where((root >= 0) & (root <= dt), root, np.inf)
    t[moving] = t_m
    return t


@dataclass(frozen=True)
class Contact:
    """One contact: step index, time within the run (s), robots i < j, approach speed along the normal (m/s)."""

    step: int
    time: float
    i: int
    j: int
    approach_speed: float


@dataclass(frozen=True)
class VerificationReport:
    """Outcome of :func:`verify`: safety score S ∈ [0, 1] and contact statistics."""

    score: float
    steps: int
    n_robots: int
    contacts: tuple[Contact, ...]
    contacts_per_robot: np.ndarray
    mean_approach_speed: float
    mean_contact_duration_s: float
    first_contact_time: float | None
    final_positions: np.ndarray = field(repr=False)

    def to_dict(self) -> dict:
        return {
            "score": float(self.score), "steps": self.steps, "n_robots": self.n_robots,
            "n_contacts": len(self.contacts),
            "contacts_per_robot": [int(v) for v in self.contacts_per_robot],
            "mean_approach_speed": float(self.mean_approach_speed),
            "mean_contact_duration_s": float(self.mean_contact_duration_s),
            "first_contact_time": self.first_contact_time,
        }


def step_contacts(x: np.ndarray, u: np.ndarray, dt: float, contact_distance: float
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Contacts of discs at ``x`` (N, 2) moving with velocities ``u`` (N, 2) for one step of ``dt`` s.

    Broad phase by k-d tree on swept discs, narrow phase :func:`first_contact_times`.
    Returns ``pairs`` (K, 2) with i < j, contact times ``t`` (K,) in [0, dt], approach speeds
    ``vn`` (K,) along the contact normal (m/s, ≥ 0), and ``t_stop`` (N,): the time each robot
    may move before its first contact (dt for robots without one; non-penetration).
    """
    n = x.shape[0]
    t_stop = np.full(n, float(dt))
    empty = np.empty((0, 2), dtype=np.int64)
    if n < 2:
        return empty, np.empty(0), np.empty(0), t_stop
    step_len = np.linalg.norm(u, axis=1) * dt
    radius = contact_distance + 2 * float(step_len.max())
    from scipy.spatial import cKDTree  # lazy: see test_devices_rps_startup_imports

    pairs = cKDTree(x).query_pairs(radius + 1e-12, output_type="ndarray")
    if not pairs.size:
        return empty, np.empty(0), np.empty(0), t_stop
    pairs = np.sort(pairs, axis=1)
    pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]  # a fixed order, whatever the tree's
    i, j = pairs[:, 0], pairs[:, 1]
    r0 = x[i] - x[j]
    vr = u[i] - u[j]
    t = first_contact_times(r0, vr, contact_distance, dt)
    hit = np.isfinite(t)
    i, j, t, r0, vr = i[hit], j[hit], t[hit], r0[hit], vr[hit]
    normal = r0 / np.maximum(np.linalg.norm(r0, axis=1), 1e-12)[:, None]
    vn = np.maximum(0.0, -np.einsum("kd,kd->k", normal, vr))
    np.minimum.at(t_stop, i, t)
    np.minimum.at(t_stop, j, t)
    return np.column_stack((i, j)).astype(np.int64), t, vn, t_stop


@dataclass
class ContactLog:
    """Running contact statistics of one run (REFERENCE.md §4): feed it :func:`step_contacts` results."""

    n_robots: int
    dt: float
    contacts: list[Contact] = field(default_factory=list)
    per_robot: np.ndarray = field(default=None)  # type: ignore[arg-type]  # filled in __post_init__
    total_vn: float = 0.0
    steps: int = 0
    durations: list[int] = field(default_factory=list)
    running: dict[tuple[int, int], int] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.per_robot is None:
            self.per_robot = np.zeros(self.n_robots, dtype=np.int64)

    def add_step(self, pairs: np.ndarray, t: np.ndarray, vn: np.ndarray) -> None:
        """Record one step's contacts (from :func:`step_contacts`)."""
        k = self.steps
        touching: set[tuple[int, int]] = set()
        for (a, b), tc, v in zip(pairs.tolist(), t.tolist(), vn.tolist()):  # contacts only, usually none
            self.contacts.append(Contact(k, k * self.dt + float(tc), int(a), int(b), float(v)))
            self.total_vn += float(v)
            touching.add((int(a), int(b)))
        if len(pairs):
            np.add.at(self.per_robot, pairs.ravel(), 1)
        for key in list(self.running):
            if key not in touching:
                self.durations.append(self.running.pop(key))
        for key in touching:
            self.running[key] = self.running.get(key, 0) + 1
        self.steps += 1

    def score(self, v_max: float) -> float:
        """S = 1 − Σ v_n / (N · steps · v_max), clipped to [0, 1]."""
        s = 1.0 - self.total_vn / (max(self.n_robots, 1) * max(self.steps, 1) * v_max)
        return float(np.clip(s, 0.0, 1.0))

    def report(self, v_max: float, final_positions: np.ndarray) -> VerificationReport:
        durations = self.durations + list(self.running.values())
        contacts = self.contacts
        return VerificationReport(
            score=self.score(v_max), steps=self.steps, n_robots=self.n_robots, contacts=tuple(contacts),
            contacts_per_robot=self.per_robot.copy(),
            mean_approach_speed=float(np.mean([c.approach_speed for c in contacts])) if contacts else 0.0,
            mean_contact_duration_s=float(np.mean(durations)) * self.dt if durations else 0.0,
            first_contact_time=contacts[0].time if contacts else None, final_positions=final_positions,
        )


def verify(x0: np.ndarray, controller: Callable[[np.ndarray, float], np.ndarray], steps: int,
           dt: float = CONTROL_PERIOD, contact_distance: float = ROBOT_DIAMETER,
           v_max: float = MAX_LINEAR_SPEED) -> VerificationReport:
    """Run ``controller(x (N, 2), t) -> u (N, 2)`` from x0 for ``steps`` steps and score it.

    The controller's commands are used as given (wrap a SafetyFilter inside it to
    verify the filtered loop). Speeds above v_max are scaled down to v_max.
    """
    x = np.array(x0, dtype=float)
    log = ContactLog(x.shape[0], dt)
    for k in range(steps):
        u = np.asarray(controller(x.copy(), k * dt), dtype=float)
        speed = np.linalg.norm(u, axis=1)
        u = u * np.minimum(1.0, v_max / np.maximum(speed, 1e-300))[:, None]
        pairs, t, vn, t_stop = step_contacts(x, u, dt, contact_distance)
        log.add_step(pairs, t, vn)
        x = x + u * t_stop[:, None]
    return log.report(v_max, x)
