"""An experiment's robots inside a larger fleet: the assigned robots as robots 0…N−1, the rest as obstacles.

After :func:`~swarmdeck.console.runtime.fleet_upkeep.set_up` picked N robots of a fleet of M
(fleet ids ``assigned[k]`` plays experiment robot k), the experiment's
:class:`~swarmdeck.console.runtime.loop.ControlLoop` runs on :class:`AssignedRobots`: both robot
ports of :mod:`swarmdeck.core.ports` over the fleet's own ports (a ``SimulatedRobots`` with
chargers, or ``NetworkRobots`` on the MQTT fleet):

* ``read`` — the fleet's reading restricted to the assigned robots, in experiment order, with ids
  ``0…N−1`` (poses, seen, battery, charging, is_virtual); an assigned robot missing from the
  fleet's reading is kept at its last pose and not seen (the loop commands it zero and the
  barrier holds it as a fixed obstacle);
* ``send`` — the experiment's commands to the assigned fleet ids, zero to every other robot
  (they stay still on their chargers);
* ``obstacles`` — the look-ahead points ``(M − N + K, 2)`` of every robot not in the experiment
  (docked robots, robots left on the floor), plus the fleet sink's own obstacles (robots the MQTT
  link excluded): fixed obstacles of the experiment's barrier, so a script cannot drive into a
  docked robot (paper §III-A);
* ``close`` — commands zero once; the fleet's ports stay open (they outlive the experiment).

The recording made from this loop holds the script's N robots; the fleet ids are in
:attr:`AssignedRobots.fleet_ids`.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.console.runtime.fleet_upkeep import rows_of
from swarmdeck.core.kinematics import lookahead_points
from swarmdeck.core.ports import CommandSink, PoseSource, SensedPoses, obstacles_of

FloatArray = NDArray[np.float64]


class AssignedRobots:
    """Fleet robots ``assigned`` ``(N,)`` (fleet ids, experiment order) as robots 0…N−1 (module docstring).

    Args:
        source, sink: the fleet's pose source and command sink (the same object for a simulation).
        assigned: ``(N,)`` fleet ids; ``assigned[k]`` is experiment robot k.
        lookahead: ℓ of the robot model, m (for the other robots' look-ahead points).
        on_read: called with every full fleet reading (e.g. to keep the fleet's status table fresh).
    """

    def __init__(self, source: PoseSource, sink: CommandSink, assigned: ArrayLike, lookahead: float,
                 on_read: Any = None) -> None:
        self.source, self.sink = source, sink
        self.fleet_ids = np.asarray(assigned, dtype=np.int64).reshape(-1).copy()
        if len(np.unique(self.fleet_ids)) != len(self.fleet_ids) or not len(self.fleet_ids):
            raise ValueError(f"assigned robots must be distinct fleet ids, got {self.fleet_ids.tolist()}")
        self.n_robots = len(self.fleet_ids)
        self.lookahead = float(lookahead)
        self.on_read = on_read
        self.name = f"{getattr(source, 'name', 'fleet')} (robots {', '.join(map(str, self.fleet_ids.tolist()))})"
        self._ids = np.arange(self.n_robots, dtype=np.int64)
        self._poses = np.zeros((self.n_robots, 3))
        self._full: SensedPoses | None = None

    # ---------------------------------------------------------------- pose source
    def read(self, now: float = 0.0) -> SensedPoses:
        full = self.source.read(now)
        self._full = full
        if self.on_read is not None:
            self.on_read(full)
        rows, present = rows_of(full.ids, self.fleet_ids)
        poses = np.where(present[:, None], np.asarray(full.poses, dtype=float)[rows], self._poses)
        self._poses = poses.copy()
        seen = present & np.asarray(full.seen, dtype=bool)[rows]

        def pick(values: Any, fill: Any, dtype: Any) -> Any:
            if values is None:
                return None
            return np.where(present, np.asarray(values, dtype=dtype)[rows], fill)

        return SensedPoses(self._ids.copy(), poses, seen, is_virtual=pick(full.is_virtual, False, bool),
                           battery=pick(full.battery, np.nan, float), charging=pick(full.charging, False, bool))

    def health(self) -> str:
        return self.source.health()

    # ---------------------------------------------------------------- command sink
    def send(self, ids: NDArray[np.int64], v: NDArray[np.float64], w: NDArray[np.float64]) -> None:
        if len(ids) != self.n_robots or np.any(np.asarray(ids) != self._ids):
            raise ValueError(f"the experiment's robots are 0..{self.n_robots - 1}, in order")
        full_ids = self._fleet_ids()
        rows, present = rows_of(full_ids, self.fleet_ids)
        fv, fw = np.zeros(len(full_ids)), np.zeros(len(full_ids))
        fv[rows[present]] = np.asarray(v, dtype=float)[present]
        fw[rows[present]] = np.asarray(w, dtype=float)[present]
        self.sink.send(full_ids, fv, fw)

    def hold(self) -> None:
        self.sink.hold()

    def obstacles(self) -> FloatArray:
        """``(K, 2)`` look-ahead points of every fleet robot outside the experiment (and the fleet sink's
        own obstacles), m."""
        full = self._full
        parts = []
        if full is not None:
            others = ~np.isin(np.asarray(full.ids, dtype=np.int64), self.fleet_ids)
            parts.append(lookahead_points(np.asarray(full.poses, dtype=float)[others], self.lookahead))
        extra = obstacles_of(self.sink)
        if extra is not None:
            parts.append(np.asarray(extra, dtype=float).reshape(-1, 2))
        return np.concatenate(parts) if parts else np.zeros((0, 2))

    def close(self) -> None:
        """Zero for every robot once; the fleet's ports stay open."""
        ids = self._fleet_ids()
        self.sink.send(ids, np.zeros(len(ids)), np.zeros(len(ids)))

    def _fleet_ids(self) -> NDArray[np.int64]:
        full = self._full if self._full is not None else self.source.read(0.0)
        return np.asarray(full.ids, dtype=np.int64)
