"""Where the loop's poses come from and where its commands go (DESIGN.md "One tick", steps 1 and 5).

A :class:`PoseSource` gives ``(ids (N,), poses (N, 3), seen (N,))`` once per
tick; a :class:`CommandSink` takes unicycle ``(v, ω)`` per robot id. The
simulated arena is both (:class:`SimulatedRobots`). Camera tracking (a pose
source) and real robots over MQTT (a sink wrapping a ``devices.transport``
Transport, :class:`TransportSink`) plug in through the same two protocols.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from swarmdeck.devices import ArenaConfig, GritsBotParams, SimulatedArena, max_robots, random_initial_poses


@dataclass(frozen=True)
class SensedPoses:
    """One reading: ids (N,) int, poses (N, 3) [x, y, θ] (m, rad), seen (N,) bool (fresh this tick)."""

    ids: NDArray[np.int64]
    poses: NDArray[np.float64]
    seen: NDArray[np.bool_]


@runtime_checkable
class PoseSource(Protocol):
    name: str

    def read(self, now: float) -> SensedPoses:
        """The robots' poses at loop time ``now`` (s)."""

    def health(self) -> str:
        """One short line for the status bar."""


@runtime_checkable
class CommandSink(Protocol):
    name: str

    def send(self, ids: NDArray[np.int64], v: NDArray[np.float64], w: NDArray[np.float64]) -> None:
        """Apply / transmit (v m/s, ω rad/s) for the given robot ids (one period)."""

    def hold(self) -> None:
        """Paused: robots stand still (a simulation does not advance)."""

    def health(self) -> str:
        """One short line for the status bar."""

    def close(self) -> None:
        """Stop the robots and release resources."""


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
                 initial_poses: Any = None) -> None:
        cfg = config if config is not None else ArenaConfig()
        if cfg.real_time:
            raise ValueError("SimulatedRobots: the console paces the loop itself; use ArenaConfig(real_time=False)")
        if initial_poses is None and n_robots > max_robots(cfg.bounds):
            # Denser than the default lattice, still barrier-safe: 0.24 m between centres keeps the
            # look-ahead points (ℓ = 0.03 m) ≥ 0.18 m > D_s apart. Raises naming the maximum if N does not fit.
            initial_poses = random_initial_poses(n_robots, cfg.bounds, spacing=0.24, min_separation=0.24,
                                                 rng=cfg.seed)
        self.sim = SimulatedArena(n_robots if initial_poses is None else None, initial_poses, config=cfg,
                                  params=params if params is not None else GritsBotParams())
        self._ids = np.arange(self.sim.n_robots, dtype=np.int64)
        self._seen = np.ones(self.sim.n_robots, dtype=bool)

    @property
    def n_robots(self) -> int:
        return int(self.sim.n_robots)

    def read(self, now: float = 0.0) -> SensedPoses:
        return SensedPoses(self._ids, self.sim.poses, self._seen)

    def send(self, ids: NDArray[np.int64], v: NDArray[np.float64], w: NDArray[np.float64]) -> None:
        if len(ids) != self.n_robots or np.any(np.asarray(ids) != self._ids):
            raise ValueError(f"simulation expects commands for ids 0..{self.n_robots - 1} in order")
        self.sim.step(v, w)

    def hold(self) -> None:
        """Paused simulation: nothing moves and simulated time stands still."""

    def health(self) -> str:
        rep = self.sim.report
        return f"sim t={self.sim.time:.1f} s, collision steps {rep.steps_with_collision}"

    def close(self) -> None:
        """Nothing to release."""


class TransportSink:
    """A command sink over a ``devices.transport`` Transport (``send(ids, v, w, leds=None)``, ``status()``,
    ``close()``), e.g. real GRITSBots over MQTT. ``hold`` sends zeros so robots brake at once."""

    def __init__(self, transport: Any, name: str = "transport") -> None:
        self.transport = transport
        self.name = name

    def send(self, ids: NDArray[np.int64], v: NDArray[np.float64], w: NDArray[np.float64]) -> None:
        self.transport.send(np.asarray(ids), np.asarray(v, dtype=float), np.asarray(w, dtype=float))

    def hold(self) -> None:
        ids = np.asarray(getattr(self.transport, "robots", lambda: [])(), dtype=np.int64)
        if len(ids):
            self.transport.send(ids, np.zeros(len(ids)), np.zeros(len(ids)))

    def health(self) -> str:
        st = self.transport.status()
        return str(st) if not isinstance(st, dict) else ", ".join(f"{k}={v}" for k, v in st.items())[:120]

    def close(self) -> None:
        try:
            self.hold()
        finally:
            self.transport.close()
