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
from scipy.spatial import cKDTree


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


def verify(x0: np.ndarray, controller: Callable[[np.ndarray, float], np.ndarray], steps: int,
           dt: float = 0.033, contact_distance: float = 0.11, v_max: float = 0.2) -> VerificationReport:
    """Run ``controller(x (N, 2), t) -> u (N, 2)`` from x0 for ``steps`` steps and score it.

    The controller's commands are used as given (wrap a SafetyFilter inside it to
    verify the filtered loop). Speeds above v_max are scaled down to v_max.
    """
    x = np.array(x0, dtype=float)
    n = x.shape[0]
    contacts: list[Contact] = []
    per_robot = np.zeros(n, dtype=np.int64)
    in_contact = np.zeros((0, 2), dtype=np.int64)
    durations: list[int] = []
    running: dict[tuple[int, int], int] = {}
    total_vn = 0.0
    for k in range(steps):
        u = np.asarray(controller(x.copy(), k * dt), dtype=float)
        speed = np.linalg.norm(u, axis=1)
        u = u * np.minimum(1.0, v_max / np.maximum(speed, 1e-300))[:, None]
        step_len = np.linalg.norm(u, axis=1) * dt
        t_stop = np.full(n, dt)
        touching: set[tuple[int, int]] = set()
        if n >= 2:
            radius = contact_distance + 2 * float(step_len.max())
            pairs = cKDTree(x).query_pairs(radius + 1e-12, output_type="ndarray")
            if pairs.size:
                i, j = pairs[:, 0], pairs[:, 1]
                r0 = x[i] - x[j]
                vr = u[i] - u[j]
                t = first_contact_times(r0, vr, contact_distance, dt)
                hit = np.isfinite(t)
                for a, b, tc, rr, vv in zip(i[hit], j[hit], t[hit], r0[hit], vr[hit]):
                    normal = rr / max(float(np.linalg.norm(rr)), 1e-12)
                    vn = max(0.0, -float(normal @ vv))
                    contacts.append(Contact(k, k * dt + float(tc), int(min(a, b)), int(max(a, b)), vn))
                    per_robot[[a, b]] += 1
                    total_vn += vn
                    t_stop[a] = min(t_stop[a], tc)
                    t_stop[b] = min(t_stop[b], tc)
                    touching.add((int(min(a, b)), int(max(a, b))))
        for key in list(running):
            if key not in touching:
                durations.append(running.pop(key))
        for key in touching:
            running[key] = running.get(key, 0) + 1
        x = x + u * t_stop[:, None]
    durations.extend(running.values())
    score = 1.0 - total_vn / (max(n, 1) * max(steps, 1) * v_max)
    return VerificationReport(
        score=float(np.clip(score, 0.0, 1.0)), steps=steps, n_robots=n, contacts=tuple(contacts),
        contacts_per_robot=per_robot,
        mean_approach_speed=float(np.mean([c.approach_speed for c in contacts])) if contacts else 0.0,
        mean_contact_duration_s=float(np.mean(durations)) * dt if durations else 0.0,
        first_contact_time=contacts[0].time if contacts else None, final_positions=x,
    )
