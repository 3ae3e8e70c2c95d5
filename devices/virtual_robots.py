"""Virtual robots beside physical ones (paper §III-C Software, "Simulation"; issue 17 item 5).

The simulator adds robots that exist only in the trusted process and interact
with the physical ones through the server: user code sees N = N_p + K robots,
the safety filter certifies all of them in one QP (a physical robot avoids a
virtual one exactly as it avoids a real one), and only an ``is_virtual`` mask
tells them apart. Physical robots come first (rows 0 … N_p−1), the K virtual
ones after them.

:class:`MixedRobots` is the robot ports (:mod:`swarmdeck.core.ports`) of any physical pose source
and command sink (the MQTT robots behind ``--robots-via``, a camera, or the simulation standing in
for hardware) plus a :class:`~swarmdeck.devices.simulated_robots.SimulatedRobots` of the K virtual
ones, stepped one period per tick. Its readings carry ``SensedPoses.is_virtual``, which the console
loop puts in every Frame and ``Arena(backend=MixedRobots(…)).is_virtual`` shows user code.

Virtual robots start on free sites at least the robots' separation away from
every physical robot (:func:`virtual_start_poses`), so the barrier starts in
its safe set.
"""
from __future__ import annotations

from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.bounds import Bounds
from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.core.ports import CommandSink, PoseSource, SensedPoses, close_ports, obstacles_of
from swarmdeck.devices.initial_conditions import random_initial_poses
from swarmdeck.devices.simulated_robots import SimulatedRobots
from swarmdeck.devices.simulator import ArenaConfig

FloatArray = NDArray[np.float64]

#: attributes of the physical pose source a caller may ask the mixed ports for (the camera picture)
_FORWARDED = ("image", "image_ref", "truth")


def virtual_start_poses(k: int, physical_xy: ArrayLike, bounds: Bounds, seed: int | None = None) -> FloatArray:
    """``(K, 3)`` random start poses for K virtual robots, each ≥ 0.23 m (the robots' start separation)
    from every other one and from every physical robot at ``physical_xy`` ``(M, 2)`` m.

    Raises ValueError naming how many fit beside the physical robots when K is too many.
    """
    return random_initial_poses(int(k), bounds, rng=seed, avoid=np.asarray(physical_xy, dtype=float).reshape(-1, 2))


def virtual_ids(k: int, physical_ids: ArrayLike) -> NDArray[np.int64]:
    """Ids for K virtual robots: the K ids after the largest physical id (``0 … K−1`` with none)."""
    phys = np.asarray(physical_ids, dtype=np.int64).reshape(-1)
    first = int(phys.max()) + 1 if len(phys) else 0
    return np.arange(first, first + int(k), dtype=np.int64)


class MixedRobots:
    """Physical robots (``source`` + ``sink``) and virtual ones (``virtual``) as one pose source and
    command sink for the console loop.

    Args:
        source, sink: the physical robots' ports (may be the same object).
        virtual: the simulated virtual robots (``SimulatedRobots``, rows in id order).
        ids: ``(K,)`` robot ids of the virtual robots, distinct from every physical id.

    Each tick :meth:`read` gives the physical reading followed by the K virtual robots (always
    seen), with ``is_virtual`` set for the latter; :meth:`send` splits the commands by id and
    steps the virtual robots one period.
    """

    def __init__(self, source: PoseSource, sink: CommandSink, virtual: SimulatedRobots, ids: ArrayLike) -> None:
        self.source, self.sink, self.virtual = source, sink, virtual
        self.virtual_ids = np.asarray(ids, dtype=np.int64).reshape(-1).copy()
        if len(self.virtual_ids) != virtual.n_robots or len(np.unique(self.virtual_ids)) != len(self.virtual_ids):
            raise ValueError(f"virtual robots need {virtual.n_robots} distinct ids, got {self.virtual_ids.tolist()}")
        self._order = np.argsort(self.virtual_ids)
        self.name = f"{getattr(source, 'name', 'robots')} + {virtual.n_robots} virtual"

    @classmethod
    def add_virtual(cls, source: PoseSource, sink: CommandSink, k: int, config: ArenaConfig,
                    params: GritsBotParams | None = None) -> MixedRobots:
        """K virtual robots beside the robots ``source`` reads now: ids after the largest physical id,
        start poses clear of every physical robot (:func:`virtual_start_poses`, seeded by ``config.seed``).

        Raises ValueError when K < 1 or the K robots do not fit beside the physical ones.
        """
        if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
            raise ValueError(f"number of virtual robots must be an integer >= 1, got {k!r}")
        now = source.read(0.0)
        poses = np.asarray(now.poses, dtype=float).reshape(-1, 3)
        start = virtual_start_poses(k, poses[:, :2], config.bounds, config.seed)
        sim = SimulatedRobots(initial_poses=start, config=config, params=params)
        return cls(source, sink, sim, virtual_ids(k, now.ids))

    # ---------------------------------------------------------------- pose source
    def read(self, now: float = 0.0) -> SensedPoses:
        """The physical reading, then the virtual robots; ``is_virtual`` marks the latter."""
        phys = self.source.read(now)
        virt = self.virtual.read(now)
        p_ids = np.asarray(phys.ids, dtype=np.int64).reshape(-1)
        n_p, k = len(p_ids), len(self.virtual_ids)
        clash = np.intersect1d(p_ids, self.virtual_ids)
        if len(clash):
            raise ValueError(f"physical robot id(s) {clash.tolist()} are also virtual robots' ids")
        battery = None if phys.battery is None else np.concatenate((phys.battery, np.full(k, np.nan)))
        charging = None if phys.charging is None else np.concatenate((phys.charging, np.zeros(k, dtype=bool)))
        return SensedPoses(
            np.concatenate((p_ids, self.virtual_ids)),
            np.concatenate((np.asarray(phys.poses, dtype=float).reshape(-1, 3), virt.poses)),
            np.concatenate((np.asarray(phys.seen, dtype=bool).reshape(-1), np.ones(k, dtype=bool))),
            is_virtual=np.concatenate((np.zeros(n_p, dtype=bool), np.ones(k, dtype=bool))),
            battery=battery, charging=charging, time=phys.time,
        )

    # ---------------------------------------------------------------- command sink
    def send(self, ids: ArrayLike, v: ArrayLike, w: ArrayLike) -> None:
        """Physical ids to the physical sink, virtual ids to the simulation (which advances one
        period; a virtual robot not named gets zero)."""
        ids = np.asarray(ids, dtype=np.int64).reshape(-1)
        v = np.asarray(v, dtype=float).reshape(-1)
        w = np.asarray(w, dtype=float).reshape(-1)
        mask = np.isin(ids, self.virtual_ids)
        self.sink.send(ids[~mask], v[~mask], w[~mask])
        rows = self._order[np.searchsorted(self.virtual_ids, ids[mask], sorter=self._order)]
        vv, ww = np.zeros(len(self.virtual_ids)), np.zeros(len(self.virtual_ids))
        vv[rows], ww[rows] = v[mask], w[mask]
        self.virtual.send(np.arange(len(vv), dtype=np.int64), vv, ww)

    def hold(self) -> None:
        """Paused: the physical robots get zero, the virtual ones stand still."""
        self.sink.hold()
        self.virtual.hold()

    def obstacles(self) -> FloatArray:
        """The physical sink's fixed obstacles ``(M, 2)`` m (robots excluded from control)."""
        obstacles = obstacles_of(self.sink)
        return np.zeros((0, 2)) if obstacles is None else np.asarray(obstacles, dtype=float).reshape(-1, 2)

    def health(self) -> str:
        parts = [self.source.health()]
        if self.sink is not cast(object, self.source):
            parts.append(f"commands: {self.sink.health()}")
        parts.append(f"virtual: {len(self.virtual_ids)} robots, {self.virtual.health()}")
        return "; ".join(parts)

    def close(self) -> None:
        """Stop and release the physical robots (sink, then a separate source) and the simulation."""
        try:
            close_ports(self.source, self.sink)
        finally:
            self.virtual.close()

    def __getattr__(self, name: str) -> Any:
        if name in _FORWARDED:
            return getattr(self.source, name)
        if name == "robot_health":  # the physical robots' firmware reports (virtual ones have none)
            return getattr(self.sink, name)
        raise AttributeError(f"{type(self).__name__} has no attribute {name!r}")
