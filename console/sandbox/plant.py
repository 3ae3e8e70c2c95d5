"""The trusted side's robots for sandboxed runs: an Arena, and the disturbed simulator verification uses.

:class:`SandboxPlant` is the sandbox's one plant: it drives a trusted
:class:`~swarmdeck.devices.Arena` (wheel limits, the barrier when on, validation;
``ArenaPlant(arena)``) or the console's control loop (the portal's arena) with the
commands the sandboxed script sends. :class:`VerificationRobots` is the robot backend under it during
verification: the simulated arena plus what a real arena adds (pose noise from
tracking, one tick of command latency, dropped commands) and the contact model
of REFERENCE.md §4 (robots are discs of the robot diameter; at a contact they
stop at the contact instant — non-penetration — and the commanded approach
speed is recorded), so the safety score S and the contact statistics come from
the same simulation.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from swarmdeck.console.runtime.network_frame import NetworkFrame
from swarmdeck.console.sandbox.network_link import TrustedNetwork
from swarmdeck.console.sandbox.protocol import ProtocolError
from swarmdeck.core.annotations import Annotations
from swarmdeck.core.annotator import Annotator
from swarmdeck.core.constants import ROBOT_DIAMETER
from swarmdeck.core.kinematics import GritsBotParams, limit_unicycle, unicycle_to_si, wrap_angle
from swarmdeck.core.obstacles import segments_near
from swarmdeck.core.ports import SensedPoses
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.clock import RealTimePacer
from swarmdeck.devices.simulator import SimulatedArena
from swarmdeck.devices.validation import ValidationReport
from swarmdeck.network import NetworkConfig
from swarmdeck.safety.verifier import ContactLog, step_contacts
from swarmdeck.sensing import SensingConfig, SensorReadings, Sensors


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


#: m of clearance within which a robot's distance to an obstacle segment is watched (:class:`Closest`)
OBSTACLE_WATCH = 0.5


@dataclass(frozen=True)
class Closest:
    """The closest approach of a run so far: clearance (m: centre distance minus the robot diameter between two
    robots, minus the radius to an obstacle segment; 0 or less is a contact), what came that close — robots
    ``(i, j)`` or robot ``i`` and segment ``k`` — and when (simulated s). Infinite before anything was near
    (obstacles are watched within :data:`OBSTACLE_WATCH`)."""

    clearance: float = float("inf")
    kind: str = ""  # "robots" or "obstacle"
    first: int = -1
    second: int = -1
    time: float = 0.0

    def robots(self, clearance: float, i: int, j: int, time: float) -> Closest:
        """This, or robots ``i``, ``j`` at ``clearance`` when they came strictly closer."""
        return Closest(clearance, "robots", min(i, j), max(i, j), time) if clearance < self.clearance else self

    def obstacle(self, clearance: float, robot: int, segment: int, time: float) -> Closest:
        """This, or robot ``robot`` at ``clearance`` from segment ``segment`` when it came strictly closer."""
        return Closest(clearance, "obstacle", robot, segment, time) if clearance < self.clearance else self


@dataclass
class VerificationRobots:
    """Robot ports (:mod:`swarmdeck.core.ports`) for the Arena: the simulator with disturbances and contacts.

    Args:
        sim: the simulated arena (true poses).
        disturbances: noise, latency, drops.
        rng: the run's generator for the disturbances.
        contact_distance: centre distance at which two robots touch, m (the robot diameter).
        offset: a constant tracking offset ``(N, 3)`` [x, y, θ] (m, rad) added to every tracked pose on top of
            the noise (the falsifier's probe, :mod:`.falsify`), or None.
    """

    sim: SimulatedArena
    disturbances: Disturbances
    rng: np.random.Generator
    contact_distance: float = ROBOT_DIAMETER
    contacts: ContactLog = field(init=False)
    min_distance: list[float] = field(init=False, default_factory=list)  # per step, m (centres)
    contact_points: list[tuple[float, float, float]] = field(init=False, default_factory=list)  # (t, x, y)
    offset: NDArray[np.float64] | None = None  # (N, 3) constant tracking offset (the falsifier's probe), or None
    closest: Closest = field(init=False)  # the closest approach of the run (the falsifier's objective)

    name = "verification (disturbed simulation)"

    def __post_init__(self) -> None:
        self.n_robots = self.sim.n
        self._ids = np.arange(self.n_robots, dtype=np.int64)
        self._seen = np.ones(self.n_robots, dtype=np.bool_)
        self.params: GritsBotParams = self.sim.params
        self.contacts = ContactLog(self.n_robots, self.sim.config.dt)
        self._pending = (np.zeros(self.n_robots), np.zeros(self.n_robots))
        self._applied = (np.zeros(self.n_robots), np.zeros(self.n_robots))
        if self.offset is not None:
            self.offset = np.array(self.offset, dtype=float).reshape(self.n_robots, 3)
        self.closest = Closest()
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
        if self.offset is not None:
            observed = observed + self.offset
        observed[:, 2] = wrap_angle(observed[:, 2])
        self._observed = observed

    def read(self, now: float = 0.0) -> SensedPoses:
        """The tracked poses (every robot seen) at the simulator's time."""
        return SensedPoses(self._ids, self._observed.copy(), self._seen, time=self.sim.time)

    def send(self, ids: NDArray[np.int64], v: ArrayLike, w: ArrayLike) -> None:
        """One period of ``(v, ω)`` for robots 0…N−1 in order (:meth:`step`)."""
        if len(ids) != self.n_robots or np.any(np.asarray(ids) != self._ids):
            raise ValueError(f"verification expects commands for ids 0..{self.n_robots - 1} in order")
        self.step(v, w)

    def hold(self) -> None:
        """Nothing moves."""

    def health(self) -> str:
        return f"simulator clock {self.sim.time:.1f} s"

    def close(self) -> None:
        """Nothing to release."""

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
            d, nearest = cKDTree(self.sim.poses[:, :2]).query(self.sim.poses[:, :2], k=2)
            self.min_distance.append(float(d[:, 1].min()))
            i = int(np.argmin(d[:, 1]))
            self.closest = self.closest.robots(float(d[i, 1]) - self.contact_distance, i, int(nearest[i, 1]),
                                               self.sim.time)
        segments = self.sim.config.segments
        if len(segments):
            near, seg, dist = segments_near(self.sim.poses[:, :2], segments, 0.5 * self.contact_distance + OBSTACLE_WATCH)
            if len(dist):
                j = int(np.argmin(dist))
                self.closest = self.closest.obstacle(float(dist[j]) - 0.5 * self.contact_distance, int(near[j]),
                                                     int(seg[j]), self.sim.time)
        self._observe()
        return self._observed.copy()


@dataclass(frozen=True)
class LoopWorld:
    """What a loop plant's sensors need of its ControlLoop: the robot model, bounds (m), period (s), obstacle
    segments (M, 2, 2) m, seed, and ``commanded() -> (v (N,), w (N,))`` the last Frame's commands."""

    robot: GritsBotParams
    bounds: Any
    dt: float
    segments: NDArray[np.float64] | None
    seed: int | None
    commanded: Callable[[], tuple[NDArray[np.float64], NDArray[np.float64]]]

    @classmethod
    def of(cls, loop: Any) -> LoopWorld:
        cfg = loop.config
        n = int(cfg.n_robots)

        def commanded() -> tuple[NDArray[np.float64], NDArray[np.float64]]:
            frame = loop.latest
            if frame is None:
                return np.zeros(n), np.zeros(n)
            return np.asarray(frame.v, dtype=float), np.asarray(frame.w, dtype=float)

        segments = None if cfg.obstacles is None else cfg.obstacles.segments
        return cls(getattr(loop, "robot", None) or GritsBotParams(), cfg.bounds, float(cfg.dt), segments,
                   None if cfg.seed is None else int(cfg.seed), commanded)


class SandboxPlant:
    """The sandbox's one :class:`~swarmdeck.console.sandbox.run.Plant`: each tick, the script's nominal
    look-ahead velocities (N, 2) go to a trusted driver that certifies them (wheel limits, the barrier,
    fail-stop, :func:`~swarmdeck.devices.pipeline.certify`) and drives the robots; the script sees the
    driver's time and poses. Two drivers, one plant:

    * :meth:`on_arena` — an :class:`~swarmdeck.devices.Arena` (``swarmdeck run --sandbox``, verification):
      NaN/inf rows are stopped and counted by the Arena; finished at its declared duration;
    * :meth:`on_loop` — the console's control loop (the portal's arena): the nominal is the loop's
      behaviour for one tick (``commands.set``), paced by ``pacer``; time is the loop's run time (it stops
      while the loop is e-stopped); finished at ``duration``.

    Args:
        n: robots the script drives.
        observe: ``() -> (time s, poses (N, 3))``.
        step: one tick with the nominal ``(N, 2)`` (None: the script missed the tick → stop).
        finished: the run's declared duration is over.
        arena: the Arena driven (:meth:`on_arena`; its report is the run's), else None.
    """

    def __init__(self, n: int, observe: Callable[[], tuple[float, NDArray[np.float64]]],
                 step: Callable[[NDArray[np.float64] | None], None], finished: Callable[[], bool],
                 arena: Arena | None = None, drawer: Annotator | None = None) -> None:
        self.n, self._observe, self._step, self._finished, self.arena = int(n), observe, step, finished, arena
        self.network: NetworkFrame | None = None  # the script's last account of its robots' traffic (display only)
        self.on_network: Callable[[NetworkFrame], None] | None = None
        self.trusted_network: TrustedNetwork | None = None  # a decentralised script's network (use_network)
        self._world: LoopWorld | None = None  # the loop driver's robots, for sensors the script asks for
        self._sensors: Sensors | None = None
        self._sensed: SensorReadings | None = None
        self.drawer = drawer if drawer is not None else (arena.draw if arena is not None else None)
        """where what the script draws goes (its Frames' annotations), capped there; None: dropped"""

    @classmethod
    def on_arena(cls, arena: Arena) -> SandboxPlant:
        """The plant on a trusted Arena."""

        def step(nominal: NDArray[np.float64] | None) -> None:
            if nominal is None:
                arena.stop()
            else:
                arena.set_velocities(nominal)
            arena.step()

        def finished() -> bool:
            d = arena.duration
            return d is not None and arena.time >= d - 1e-9

        return cls(arena.n, lambda: (arena.time, arena.poses()), step, finished, arena)

    @classmethod
    def on_loop(cls, loop: Any, commands: Any, duration: float, pacer: RealTimePacer | None) -> SandboxPlant:
        """The plant on a ControlLoop whose behaviour is ``commands`` (``set(nominal)`` before each tick)."""
        n = int(loop.config.n_robots)
        drawer = getattr(commands, "draw", None)

        def observe() -> tuple[float, NDArray[np.float64]]:
            frame = loop.latest
            return loop.run_time, (frame.poses.copy() if frame is not None else np.zeros((n, 3)))

        def step(nominal: NDArray[np.float64] | None) -> None:
            commands.set(nominal)
            loop.tick()
            if pacer is not None:
                pacer.wait()

        plant = cls(n, observe, step, lambda: loop.run_time >= duration - 1e-9,
                    drawer=drawer if isinstance(drawer, Annotator) else None)
        plant._world = LoopWorld.of(loop)
        if hasattr(commands, "network"):  # a behaviour that reports it puts it in the loop's Frames (behaviours.ReportsNetwork)
            plant.on_network = lambda frame: setattr(commands, "network", frame)
        return plant

    def observe(self) -> tuple[float, NDArray[np.float64]]:
        return self._observe()

    def use_sensors(self, config: SensingConfig | None) -> None:
        """The sensors the script asked for (its ``sensors`` message), simulated here: on the driver's Arena (its seed,
        its obstacles, the commands the robots really ran; a robot port with its own readings gives those), or for
        the loop driver from the loop's Frames (their poses and the commands sent, ``v``, ``w``)."""
        if self.arena is not None:
            self.arena.use_sensors(config)
            return
        self._sensors = None if config is None or self._world is None else Sensors(
            self.n, config, rng=np.random.default_rng(self._world.seed), params=self._world.robot,
            bounds=self._world.bounds, obstacles=self._world.segments)
        self._sensed = None if self._sensors is None else self._sensors.first(self.observe()[1])

    def set_leds(self, rgb: NDArray[np.uint8]) -> None:
        """The LEDs ``(N, 3)`` 0…255 the script set (its ``leds`` message): shown (and sent to robots with LEDs)."""
        if self.arena is not None and self.arena.sensors is not None and self.arena.sensors.config.leds:
            self.arena.set_leds(rgb)

    def use_network(self, config: NetworkConfig) -> None:
        """A decentralised script's network (its ``decentralised`` message), modelled here: the script's messages go
        through it (:meth:`post_messages`), it steps at the robots' true positions after every tick, and what it
        shows is its own traffic, not the script's account."""
        self.trusted_network = TrustedNetwork(self.n, config, self.observe()[1][:, :2])

    def post_messages(self, message: dict[str, Any]) -> None:
        """The script's ``outbox`` message for this tick (refusals counted by the network)."""
        if self.trusted_network is None:
            raise ProtocolError("an 'outbox' message before the network's configuration")
        self.trusted_network.post(message)

    def inboxes(self, k: int) -> dict[str, Any] | None:
        """The ``inboxes`` message of tick ``k`` (None: no network)."""
        return None if self.trusted_network is None else self.trusted_network.inboxes_message(k)

    def readings(self) -> SensorReadings | None:
        """What the robots sensed in the last tick (sent to the script before the next poses); None without
        sensors."""
        if self.arena is None:
            return self._sensed
        return None if self.arena.sensors is None else self.arena.sense()

    def add_obstacles(self, obstacles: NDArray[np.float64]) -> None:
        """The script's declared obstacle segments ``(M, 2, 2)`` m, solid from now on (:meth:`Arena.add_obstacles`:
        barrier, contact, validation, sensors); ValueError naming a bad segment. A loop plant takes them where its
        loop is built (the portal's ``make_plant(..., obstacles=)``)."""
        if self.arena is None:
            raise ValueError("the script declares obstacles, and this arena cannot make them solid")
        self.arena.add_obstacles(obstacles)

    def draw(self, ann: Annotations) -> None:
        """What the script draws from the next tick on (its ``draw`` message, structure checked by the
        protocol): replaces what it drew before; the caps (NaN refused, clipped to the arena, at most
        ``max_primitives`` …) apply in the drawer, which counts every cap hit."""
        if self.drawer is not None:
            self.drawer.add(ann, key="sandboxed script")

    def apply(self, nominal: NDArray[np.float64] | None) -> None:
        """One tick: the script's nominal look-ahead velocities (N, 2) through the driver's pipeline; None: stop."""
        self._step(nominal)
        if self.trusted_network is not None:
            traffic = self.trusted_network.step(self.observe()[1][:, :2])
            self.show_network(traffic.links.astype(np.int64), traffic.messages / self._dt())
        if self._sensors is not None and self._world is not None:
            v, w = self._world.commanded()
            self._sensed = self._sensors.update(self.observe()[1], v, w, self._world.dt)

    def finished(self) -> bool:
        return self._finished()

    def _dt(self) -> float:
        """The control period, s."""
        if self.arena is not None:
            return float(self.arena.config.dt)
        return self._world.dt if self._world is not None else 1.0

    def show_network(self, links: NDArray[np.int64], rate: NDArray[np.float64]) -> None:
        """The sandboxed script's account of its network this tick (checked by ``protocol.network_traffic``):
        links (E, 2), messages/s (E,). Shown and recorded; nothing else depends on it."""
        self.network = NetworkFrame(links, rate)
        if self.on_network is not None:
            self.on_network(self.network)


def with_obstacles(config: Any, obstacles: ArrayLike) -> Any:
    """``config.obstacles`` (an Obstacles or None) with the segments ``obstacles`` ``(M, 2, 2)`` m added, as one
    :class:`~swarmdeck.core.obstacles.Obstacles` (ObstacleError, a ValueError, naming a bad segment)."""
    from swarmdeck.core.obstacles import Obstacles

    new = Obstacles.of(np.asarray(obstacles, dtype=float))
    old = config.obstacles
    return new if old is None else Obstacles(np.concatenate([Obstacles.of(old).segments, new.segments]))


def script_obstacles_config(config: Any, obstacles: ArrayLike, poses: ArrayLike) -> Any:
    """``config`` (a frozen configuration with ``obstacles`` and ``bounds``, e.g. a ``LoopConfig``) with the
    obstacle segments a sandboxed script declared (``(M, 2, 2)`` m) added to its own: the portal's loop is built
    with them (barrier, guard, Frames). ObstacleError (ValueError) naming a segment that is invalid, outside the
    bounds or within START_CLEARANCE of a start pose ``poses`` (N, 3)."""
    from dataclasses import replace

    from swarmdeck.core.bounds import Bounds
    from swarmdeck.core.obstacles import START_CLEARANCE

    merged = with_obstacles(config, obstacles).check_inside(Bounds.of(config.bounds))
    merged.check_clear(np.asarray(poses, dtype=float), START_CLEARANCE, "start pose")
    return replace(config, obstacles=merged)


#: the plant on a trusted Arena (``ArenaPlant(arena)``: ``swarmdeck run --sandbox``, verification, the tests)
ArenaPlant = SandboxPlant.on_arena
