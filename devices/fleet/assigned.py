"""An experiment's robots inside a larger fleet: the assigned robots as robots 0…N−1, the rest as obstacles.

After N robots of a fleet of M were assigned (fleet ids ``assigned[k]`` plays experiment robot k) —
by :meth:`~swarmdeck.devices.fleet.manager.FleetManager.setup` (``Arena(from_docks=True)``,
``swarmdeck run --from-docks``) or by the console's and the portal's set-up
(:mod:`swarmdeck.console.runtime.fleet_upkeep`) — the experiment runs on :class:`AssignedRobots`:
both robot ports of :mod:`swarmdeck.core.ports` over the fleet's own ports (a ``FleetManager``, a
``SimulatedRobots`` with chargers, or ``NetworkRobots`` on the MQTT fleet):

* ``read`` — the fleet's reading restricted to the assigned robots, in experiment order, with ids
  ``0…N−1`` (poses, seen, battery, charging, is_virtual; ``time`` from the experiment's start, standing
  still after :meth:`AssignedRobots.end`); an assigned robot missing from the fleet's reading is kept at
  its last pose and not seen (the loop commands it zero and the barrier holds it as a fixed obstacle);
* ``send`` — the experiment's commands to the assigned fleet ids, zero to every other robot
  (they stay still on their chargers);
* ``obstacles`` — the look-ahead points ``(M − N + K, 2)`` of every robot not in the experiment
  (docked robots, robots left on the floor), plus the fleet sink's own obstacles (robots the MQTT
  link excluded): fixed obstacles of the experiment's barrier, so a script cannot drive into a
  docked robot (paper §III-A);
* ``close`` — commands zero once; the fleet's ports stay open (they outlive the experiment).

With ``validate`` (the arena's bounds and robot model) every ``send`` also counts the experiment's own
boundary, collision and actuator errors in :attr:`AssignedRobots.report`, as the simulator does.
A recording made from these ports holds the script's N robots; the fleet ids are in
:attr:`AssignedRobots.fleet_ids`.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.bounds import Bounds
from swarmdeck.core.kinematics import GritsBotParams, limit_unicycle, lookahead_points
from swarmdeck.core.ports import SensedPoses, obstacles_of, rows_of
from swarmdeck.devices.validation import ValidationReport

FloatArray = NDArray[np.float64]


class AssignedRobots:
    """Fleet robots ``assigned`` ``(N,)`` (fleet ids, experiment order) as robots 0…N−1 (module docstring).

    Args:
        source, sink: the fleet's pose source and command sink (the same object for a simulation).
        assigned: ``(N,)`` fleet ids; ``assigned[k]`` is experiment robot k.
        lookahead: ℓ of the robot model, m (for the other robots' look-ahead points).
        on_read: called with every full fleet reading (e.g. to keep the fleet's status table fresh).
        validate: ``(bounds, robot model)``: count the experiment's validation errors in :attr:`report`.
    """

    def __init__(self, source: Any, sink: Any, assigned: ArrayLike, lookahead: float,
                 on_read: Any = None, validate: tuple[Bounds, GritsBotParams] | None = None) -> None:
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
        self._t0: float | None = None  # the fleet's clock when the experiment started (first reading)
        self._end: float | None = None  # the fleet's clock when the experiment ended
        self._validate = validate
        self.report: ValidationReport | None = None if validate is None else ValidationReport(self.n_robots)

    # ---------------------------------------------------------------- pose source
    def read(self, now: float = 0.0) -> SensedPoses:
        full = self.source.read(now)
        self._full = full
        if self._t0 is None and full.time is not None:
            self._t0 = float(full.time)
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
                           battery=pick(full.battery, np.nan, float), charging=pick(full.charging, False, bool),
                           time=self._time(full.time))

    def _time(self, fleet_time: float | None) -> float | None:
        if fleet_time is None or self._t0 is None:
            return None
        return float((fleet_time if self._end is None else self._end) - self._t0)

    @property
    def time(self) -> float | None:
        """s since the experiment started on the fleet's simulated clock (stands still after :meth:`end`;
        None for robots in the real world)."""
        full = self._full if self._full is not None else self.read()
        return self._time(full.time if self._end is None else self._end)

    def end(self) -> None:
        """The experiment is over (its robots go back to the chargers): its clock stands still from here."""
        full = self.source.read(0.0)
        if full.time is not None and self._end is None:
            self._end = float(full.time)

    def health(self) -> str:
        return self.source.health()

    # ---------------------------------------------------------------- command sink
    def send(self, ids: NDArray[np.int64], v: NDArray[np.float64], w: NDArray[np.float64]) -> None:
        if len(ids) != self.n_robots or np.any(np.asarray(ids) != self._ids):
            raise ValueError(f"the experiment's robots are 0..{self.n_robots - 1}, in order")
        full_ids = self._fleet_ids()
        rows, present = rows_of(full_ids, self.fleet_ids)
        v = np.asarray(v, dtype=float).reshape(-1)
        w = np.asarray(w, dtype=float).reshape(-1)
        fv, fw = np.zeros(len(full_ids)), np.zeros(len(full_ids))
        fv[rows[present]] = v[present]
        fw[rows[present]] = w[present]
        self.sink.send(full_ids, fv, fw)
        if self.report is not None and self._validate is not None:
            bounds, robot = self._validate
            invalid = ~(np.isfinite(v) & np.isfinite(w))
            _, _, saturated = limit_unicycle(np.where(invalid, 0.0, v), np.where(invalid, 0.0, w), robot)
            reading = self.read()
            self.report.record(reading.poses, bounds, saturated, invalid, reading.time or 0.0)

    def hold(self) -> None:
        self.sink.hold()

    def obstacles(self) -> FloatArray:
        """``(K, 2)`` look-ahead points of every fleet robot outside the experiment (and the fleet sink's
        own obstacles), m."""
        full = self._full if self._full is not None else self.source.read(0.0)
        others = ~np.isin(np.asarray(full.ids, dtype=np.int64), self.fleet_ids)
        parts = [lookahead_points(np.asarray(full.poses, dtype=float)[others], self.lookahead)]
        extra = obstacles_of(self.sink)
        if extra is not None:
            parts.append(np.asarray(extra, dtype=float).reshape(-1, 2))
        return np.concatenate(parts)

    def close(self) -> None:
        """Zero for every robot once; the fleet's ports stay open."""
        ids = self._fleet_ids()
        self.sink.send(ids, np.zeros(len(ids)), np.zeros(len(ids)))

    def _fleet_ids(self) -> NDArray[np.int64]:
        full = self._full if self._full is not None else self.source.read(0.0)
        return np.asarray(full.ids, dtype=np.int64)
