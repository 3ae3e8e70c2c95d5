"""The trusted side's robots for sandboxed runs: an Arena, and the disturbed simulator verification uses.

:class:`ArenaPlant` drives a trusted :class:`~swarmdeck.devices.Arena` (wheel
limits, the barrier when on, validation) with the commands the sandboxed script
sends. :class:`VerificationRobots` is the robot backend under it during
verification: the simulated arena plus what a real arena adds (pose noise from
tracking, one tick of command latency, dropped commands) and the contact model
of REFERENCE.md §4 (robots are discs of the robot diameter; at a contact they
stop at the contact instant — non-penetration — and the commanded approach
speed is recorded), so the safety score S and the contact statistics come from
the same simulation.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from swarmdeck.core.kinematics import GritsBotParams, limit_unicycle, unicycle_to_si
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.gritsbot import wrap_angle
from swarmdeck.devices.simulator import SimulatedArena
from swarmdeck.devices.validation import ValidationReport
from swarmdeck.safety.verifier import ContactLog, step_contacts


@dataclass(frozen=True)
class Disturbances:
    """What a real arena adds to the simulation (REFERENCE.md §1, §7).

    Attributes:
        pose_noise_xy: standard deviation of tracked x, y, m (overhead ArUco tracking: ~1–2 mm).
        pose_noise_theta: standard deviation of tracked θ, rad.
        latency_ticks: commands reach the robots this many control periods late (0 or 1).
        drop_probability: chance per robot and tick that a command is lost (the robot keeps
            its previous command, as GRITSBot firmware does until its timeout).
    """

    pose_noise_xy: float = 0.002
    pose_noise_theta: float = 0.01
    latency_ticks: int = 1
    drop_probability: float = 0.01

    def __post_init__(self) -> None:
        if not (self.pose_noise_xy >= 0 and self.pose_noise_theta >= 0):
            raise ValueError("pose noise must be >= 0")
        if self.latency_ticks not in (0, 1):
            raise ValueError(f"latency_ticks must be 0 or 1, got {self.latency_ticks!r}")
        if not 0 <= self.drop_probability < 1:
            raise ValueError(f"drop_probability must be in [0, 1), got {self.drop_probability!r}")

    def to_dict(self) -> dict:
        return {"pose_noise_xy": self.pose_noise_xy, "pose_noise_theta": self.pose_noise_theta,
                "latency_ticks": self.latency_ticks, "drop_probability": self.drop_probability}


@dataclass
class VerificationRobots:
    """A :class:`~swarmdeck.devices.backend.RobotBackend`: the simulator with disturbances and contacts.

    Args:
        sim: the simulated arena (true poses).
        disturbances: noise, latency, drops.
        rng: the run's generator for the disturbances.
        contact_distance: centre distance at which two robots touch, m (the robot diameter).
    """

    sim: SimulatedArena
    disturbances: Disturbances
    rng: np.random.Generator
    contact_distance: float = 0.11
    contacts: ContactLog = field(init=False)
    min_distance: list[float] = field(init=False, default_factory=list)  # per step, m (centres)
    contact_points: list[tuple[float, float, float]] = field(init=False, default_factory=list)  # (t, x, y)

    def __post_init__(self) -> None:
        self.n_robots = self.sim.n_robots
        self.params: GritsBotParams = self.sim.params
        self.contacts = ContactLog(self.n_robots, self.sim.config.dt)
        self._pending = (np.zeros(self.n_robots), np.zeros(self.n_robots))
        self._applied = (np.zeros(self.n_robots), np.zeros(self.n_robots))
        self._observe()

    @property
    def report(self) -> ValidationReport:
        return self.sim.report

    @property
    def time(self) -> float:
        return self.sim.time

    @property
    def poses(self) -> NDArray[np.float64]:
        """The tracked poses (true poses plus tracking noise), (N, 3)."""
        return self._observed.copy()

    @property
    def true_poses(self) -> NDArray[np.float64]:
        return self.sim.poses

    def _observe(self) -> None:
        d = self.disturbances
        noise = self.rng.normal(size=(self.n_robots, 3)) * np.array([d.pose_noise_xy, d.pose_noise_xy, d.pose_noise_theta])
        observed = self.sim.poses + noise
        observed[:, 2] = wrap_angle(observed[:, 2])
        self._observed = observed

    def step(self, v: ArrayLike, w: ArrayLike) -> NDArray[np.float64]:
        """Apply (v, ω) (N,) each, subject to latency, drops and non-penetration; returns the tracked poses."""
        v = np.asarray(v, dtype=float).reshape(-1)
        w = np.asarray(w, dtype=float).reshape(-1)
        if self.disturbances.latency_ticks:
            (v, w), self._pending = self._pending, (v, w)
        dropped = self.rng.random(self.n_robots) < self.disturbances.drop_probability
        v = np.where(dropped, self._applied[0], v)
        w = np.where(dropped, self._applied[1], w)
        finite = np.isfinite(v) & np.isfinite(w)
        v, w = np.where(finite, v, 0.0), np.where(finite, w, 0.0)
        v, w, _ = limit_unicycle(v, w, self.params)
        self._applied = (v, w)
        poses = self.sim.poses
        centres = poses[:, :2]
        u = unicycle_to_si(poses, v, w, 0.0)  # velocity of the centre (look-ahead ℓ = 0)
        dt = self.sim.config.dt
        pairs, t, vn, t_stop = step_contacts(centres, u, dt, self.contact_distance)
        if len(pairs) and len(self.contact_points) < 200:
            mid = 0.5 * (centres[pairs[:, 0]] + u[pairs[:, 0]] * t[:, None] + centres[pairs[:, 1]] + u[pairs[:, 1]] * t[:, None])
            for (x, y), tc in zip(mid.tolist(), t.tolist()):  # contacts only
                self.contact_points.append((self.sim.time + tc, x, y))
        self.contacts.add_step(pairs, t, vn)
        scale = t_stop / dt  # non-penetration: robots in contact stop at the contact instant
        self.sim.step(v * scale, w * scale)
        if self.n_robots >= 2:
            d, _ = cKDTree(self.sim.poses[:, :2]).query(self.sim.poses[:, :2], k=2)
            self.min_distance.append(float(d[:, 1].min()))
        self._observe()
        return self._observed.copy()


class ArenaPlant:
    """The sandbox's :class:`~swarmdeck.console.jobs.sandbox.Plant` on a trusted Arena."""

    def __init__(self, arena: Arena) -> None:
        self.arena = arena
        self.n = arena.n

    def observe(self) -> tuple[float, NDArray[np.float64]]:
        return self.arena.time, self.arena.poses()

    def apply(self, nominal: NDArray[np.float64] | None) -> None:
        """One tick: the script's nominal look-ahead velocities (N, 2) through this Arena's pipeline
        (wheel limits, barrier when on; NaN/inf rows stopped and counted); None: stop."""
        if nominal is None:
            self.arena.stop()
        else:
            self.arena.set_velocities(nominal)
        self.arena.step()

    def finished(self) -> bool:
        d = self.arena.duration
        return d is not None and self.arena.time >= d - 1e-9
