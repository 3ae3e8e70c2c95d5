"""The simulated arena as robot ports (the console loop's and the Arena's): pose source and command sink in one.

:class:`SimulatedRobots` is the :class:`~swarmdeck.core.ports.PoseSource` and
:class:`~swarmdeck.core.ports.CommandSink` of a :class:`SimulatedArena` (no
hardware): every robot is seen every tick, each ``send`` steps the simulation
one period on its virtual clock (every reading carries it as ``SensedPoses.time``),
``hold`` leaves it standing still. ``SimulatedRobots(sim=SimulatedArena(...))`` wraps
physics built already (the Arena's default robots, which pace themselves when
``ArenaConfig.real_time``).

With ``chargers`` (a :class:`~swarmdeck.devices.chargers.ChargerLayout`) the robots have
batteries, as the networked fleet does: robots docked on a slot charge, the others drain as
they drive (:func:`~swarmdeck.devices.battery.battery_step`), and every reading carries
their voltage and charging state; ``start_docked`` puts robot k on slot k.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.core.ports import SensedPoses
from swarmdeck.devices.battery import BatteryParams, battery_step
from swarmdeck.devices.chargers import ChargerLayout
from swarmdeck.devices.initial_conditions import max_robots, random_initial_poses
from swarmdeck.devices.simulator import ArenaConfig, SimulatedArena


class SimulatedRobots:
    """The simulated arena as pose source and command sink (no hardware).

    Args:
        n_robots: N (random non-overlapping poses from ``seed``), ignored if ``initial_poses``.
        config: arena bounds and period (``real_time`` must be False: the loop paces itself).
        params: robot model.
        initial_poses: optional ``(N, 3)`` float array.
    """

    name = "simulation"

    def __init__(self, n_robots: int = 12, config: ArenaConfig | None = None, params: GritsBotParams | None = None,
                 initial_poses: Any = None, *, chargers: ChargerLayout | None = None, start_docked: bool = False,
                 charge: Any = 1.0, battery: BatteryParams | None = None, sim: SimulatedArena | None = None) -> None:
        if sim is not None:  # the physics built already (the Arena's: it paces itself when real_time)
            self._attach(sim, chargers, charge, battery)
            return
        cfg = config if config is not None else ArenaConfig()
        if start_docked:
            if chargers is None:
                raise ValueError("SimulatedRobots: start_docked needs chargers")
            docks = chargers.dock_poses()
            if n_robots > len(docks):
                raise ValueError(f"{n_robots} robots cannot start docked: the charging strips have {len(docks)} slots")
            initial_poses = docks[:n_robots]
        if cfg.real_time:
            raise ValueError("SimulatedRobots: the console paces the loop itself; use ArenaConfig(real_time=False)")
        if initial_poses is None and n_robots > max_robots(cfg.bounds):
            # Denser than the default lattice, still barrier-safe: 0.24 m between centres keeps the
            # look-ahead points (ℓ = 0.03 m) ≥ 0.18 m > D_s apart. Raises naming the maximum if N does not fit.
            initial_poses = random_initial_poses(n_robots, cfg.bounds, spacing=0.24, min_separation=0.24,
                                                 rng=cfg.seed)
        self._attach(SimulatedArena(n_robots if initial_poses is None else None, initial_poses, config=cfg,
                                    params=params if params is not None else GritsBotParams()),
                     chargers, charge, battery)

    def _attach(self, sim: SimulatedArena, chargers: ChargerLayout | None, charge: Any,
                battery: BatteryParams | None) -> None:
        self.sim = sim
        self._ids = np.arange(self.sim.n, dtype=np.int64)
        self._seen = np.ones(self.sim.n, dtype=np.bool_)
        self.chargers = chargers
        self.battery = battery if battery is not None else BatteryParams()
        self.charge: NDArray[np.float64] | None = None
        if chargers is not None:
            self.charge = np.broadcast_to(np.asarray(charge, dtype=float), (self.sim.n,)).copy()
            if not np.all(((self.charge >= 0.0) & (self.charge <= 1.0)) | np.isnan(self.charge)):
                raise ValueError(f"charge must be in [0, 1] (NaN: a battery that reads NaN), got {self.charge.tolist()}")

    @property
    def n_robots(self) -> int:
        return self.sim.n

    @property
    def params(self) -> GritsBotParams:
        """The robot model of the simulation."""
        return self.sim.params

    @property
    def applied(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The ``(v, ω)`` the simulation applied in the last period, after limits (copies)."""
        return self.sim.applied

    @property
    def report(self) -> Any:
        """The simulator's validation counts (boundary, collisions, actuator limits)."""
        return self.sim.report

    def docked(self) -> NDArray[np.bool_]:
        """``(N,)`` robots docked on a charger slot (all False without chargers)."""
        if self.chargers is None:
            return np.zeros(self.n_robots, dtype=bool)
        return self.chargers.docked_slot(self.sim.poses) >= 0

    def truth(self, now: float = 0.0) -> NDArray[np.float64]:
        """The simulator's true poses ``(N, 3)`` (what a synthetic overhead camera renders)."""
        return self.sim.poses

    def read(self, now: float = 0.0) -> SensedPoses:
        if self.charge is None:
            return SensedPoses(self._ids, self.sim.poses, self._seen, time=self.sim.time)
        return SensedPoses(self._ids, self.sim.poses, self._seen, battery=self.battery.voltage(self.charge),
                           charging=self.docked(), time=self.sim.time)

    def send(self, ids: NDArray[np.int64], v: NDArray[np.float64], w: NDArray[np.float64]) -> None:
        if len(ids) != self.n_robots or np.any(np.asarray(ids) != self._ids):
            raise ValueError(f"simulation expects commands for ids 0..{self.n_robots - 1} in order")
        docked = self.docked() if self.charge is not None else None
        self.sim.step(v, w)
        if self.charge is not None and docked is not None:
            av, aw = self.sim.applied
            self.charge = battery_step(self.charge, self.sim.config.dt, av, aw, docked & self.docked(),
                                       self.sim.params, self.battery)

    def hold(self) -> None:
        """Paused simulation: nothing moves and simulated time stands still."""

    def health(self) -> str:
        rep = self.sim.report
        # the simulator's own clock: it stands still while paused, so it is labelled apart from session t
        return f"simulator clock {self.sim.time:.1f} s, collision steps {rep.steps_with_collision}"

    def close(self) -> None:
        """Nothing to release."""
