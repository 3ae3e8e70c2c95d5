"""Contacts between robots, on every run, counted once per episode.

Two robots are in contact by the rps test (REFERENCE.md §1,
:func:`swarmdeck.devices.validation.colliding_pairs`: centres shifted 0.025 m ahead along the heading at
most 0.135 m apart). :class:`ContactWatch` is fed each tick's poses on the trusted side (the control loop)
and reports the pairs that came into contact this tick: a pair in contact for many ticks is one episode,
and touching again after separating is a new one.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from swarmdeck.devices.validation import ValidationRules, colliding_pairs


@dataclass(frozen=True)
class Contact:
    """One contact episode: its first tick and time (s of run time), the two robots' ids and their shifted
    centres' distance then (m)."""

    tick: int
    time: float
    robots: tuple[int, int]
    distance: float

    def to_dict(self) -> dict[str, object]:
        return {"tick": self.tick, "t": round(self.time, 3), "robots": list(self.robots),
                "distance": round(self.distance, 4)}

    def message(self) -> str:
        return (f"CONTACT: robots {self.robots[0]} and {self.robots[1]} touch at t = {self.time:.2f} s "
                f"(centres {self.distance:.3f} m apart)")


class ContactWatch:
    """Contact episodes of one run (module docstring). ``episodes``: every episode so far, in order."""

    def __init__(self, rules: ValidationRules = ValidationRules()) -> None:
        self.rules = rules
        self.episodes: list[Contact] = []
        self._touching: frozenset[tuple[int, int]] = frozenset()

    @property
    def touching(self) -> frozenset[tuple[int, int]]:
        """The id pairs in contact at the last update."""
        return self._touching

    def update(self, tick: int, time: float, ids: NDArray[np.int64], poses: NDArray[np.float64],
               seen: NDArray[np.bool_]) -> list[Contact]:
        """The episodes that start this tick (pairs of seen robots in contact now and not at the last update)."""
        idx = np.flatnonzero(seen)
        pairs = colliding_pairs(poses[idx], self.rules)
        if len(pairs) == 0:
            self._touching = frozenset()
            return []
        a, b = ids[idx[pairs[:, 0]]], ids[idx[pairs[:, 1]]]
        keys = [(int(min(x, y)), int(max(x, y))) for x, y in zip(a, b)]  # the few pairs in contact
        shifted = poses[idx][:, :2] + self.rules.collision_shift * np.column_stack(
            (np.cos(poses[idx][:, 2]), np.sin(poses[idx][:, 2])))
        dist = np.linalg.norm(shifted[pairs[:, 0]] - shifted[pairs[:, 1]], axis=1)
        new = [Contact(int(tick), float(time), key, float(d)) for key, d in zip(keys, dist)
               if key not in self._touching]
        self._touching = frozenset(keys)
        self.episodes.extend(new)
        return new

    def summary(self) -> dict[str, object]:
        """For run.json: ``{"count", "robots": ids involved, "episodes": the first 100}``."""
        robots = sorted({r for c in self.episodes for r in c.robots})
        return {"count": len(self.episodes), "robots": robots,
                "episodes": [c.to_dict() for c in self.episodes[:100]]}
