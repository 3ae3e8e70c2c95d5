"""The one place that decides which robots a run drives: :class:`RobotsSpec` → :func:`open_robots`.

Every composition root — ``swarmdeck console``, ``swarmdeck fleet``, the portal's arena
(:mod:`swarmdeck.console.portal.arena_fleet`) and ``swarmdeck run`` — describes its robots with a
frozen :class:`RobotsSpec` and gets the robot ports of :mod:`swarmdeck.core.ports` (a
``PoseSource`` and a ``CommandSink``) from :func:`open_robots`:

* simulated (``robots_via`` None) → ``devices.simulated_robots.SimulatedRobots`` (the simulator's
  truth; with ``docked`` robot k starts on charger slot k, with batteries that charge there and
  drain while driving);
* ``robots_via="mqtt://HOST:PORT"`` → ``devices.net.console_robots.NetworkRobots`` (an
  ``MqttTransport`` behind the ``CommandStreamer`` watchdogs: stale poses, stale inputs and missing
  robots get zero; missing robots become barrier obstacles), poses from the robots' pose topic;
* ``camera`` (``synthetic``, a webcam INDEX, a stream URL, a video FILE, a folder of images) →
  ``tracking.TrackedPoseSource`` as the pose source: ``synthetic`` renders the robots the command
  sink knows (the simulator's truth, or the poses the MQTT robots report), so the whole camera →
  ArUco → homography → poses path runs with no hardware;
* ``virtual`` K → ``devices.virtual_robots.MixedRobots``: K robots simulated here beside the others,
  one object as both ports.

Robots without a fresh pose are "not seen": the loop commands them zero and the barrier treats
them as fixed obstacles. To add a robot transport (docs/architecture.md): one ports class in ``devices/``,
one field of :class:`RobotsSpec` and one branch of :func:`open_robots` here.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds, check_bounds
from swarmdeck.core.constants import CONTROL_PERIOD
from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.core.obstacles import Obstacles
from swarmdeck.core.ports import CommandSink, PoseSource

if TYPE_CHECKING:
    from swarmdeck.devices.net.console_robots import NetworkRobots
    from swarmdeck.tracking import TrackedPoseSource


@dataclass(frozen=True)
class RobotsSpec:
    """Which robots to drive (module docstring). Units: m, s.

    Attributes:
        n_robots: N robots (ids 0…N−1). MQTT: None uses every robot heard of within ``wait_for_poses``.
        bounds: the arena ``(x0, x1, y0, y1)``, m.
        dt: the control period, s (the simulation's step).
        seed: seed of random start poses (simulated and virtual robots).
        robots_via: ``mqtt://HOST:PORT`` of GRITSBots or ``swarmdeck robots``; None: simulated.
        docked: simulated robots start on the charger slots along the walls, with batteries.
        charge: simulated robots' initial state of charge in [0, 1], one for all or one per robot (NaN: a
            battery that reads NaN), with ``docked`` or ``chargers``.
        chargers: simulated robots have batteries and charger slots even when they start on the floor.
        camera: track the robots with an overhead camera (None: poses from the robots' own port).
        virtual: K virtual robots simulated beside the others (0: none).
        wait_for_poses: MQTT: s to wait for the first pose of every robot.
        partial: MQTT with ``n_robots``: go on after the wait if at least one robot reported.
        params: the robot model.
        obstacles: line-segment obstacles on the floor (:class:`~swarmdeck.core.obstacles.Obstacles`): solid for
            simulated robots (and virtual ones); a charger slot on one is refused naming both.
    """

    n_robots: int | None = 12
    bounds: Bounds = DEFAULT_BOUNDS
    dt: float = CONTROL_PERIOD
    seed: int | None = None
    robots_via: str | None = None
    docked: bool = False
    charge: float | tuple[float, ...] = 1.0
    chargers: bool = False
    camera: str | None = None
    virtual: int = 0
    wait_for_poses: float = 5.0
    partial: bool = False
    params: GritsBotParams = field(default_factory=GritsBotParams)
    obstacles: Obstacles | None = None

    def __post_init__(self) -> None:
        check_bounds(self.bounds, "RobotsSpec.bounds")
        if self.n_robots is not None and (isinstance(self.n_robots, bool) or self.n_robots < 1):
            raise ValueError(f"RobotsSpec.n_robots must be >= 1, got {self.n_robots!r}")
        if self.n_robots is None and self.robots_via is None:
            raise ValueError("RobotsSpec.n_robots: simulated robots need a number")
        if self.docked and (self.robots_via is not None or self.camera is not None):
            raise ValueError("docked places simulated robots; physical robots start where they are "
                             "(`swarmdeck robots --start docked` for the simulated MQTT fleet)")
        if isinstance(self.virtual, bool) or self.virtual < 0:
            raise ValueError(f"RobotsSpec.virtual must be a number of robots >= 0, got {self.virtual!r}")

    @property
    def simulated(self) -> bool:
        """The robots are simulated here (no ``robots_via``)."""
        return self.robots_via is None

    def source_name(self) -> str:
        """What the recording says the robots were (a broker's password never shows)."""
        if self.camera:
            return self.camera
        if self.robots_via:
            from swarmdeck.devices.net.mqtt_config import redact_url

            return redact_url(self.robots_via)
        return "simulation"


@dataclass(frozen=True)
class RobotPorts:
    """The robots' ports: where poses come from and where commands go (the same object for a
    simulation, for MQTT robots without a camera and for mixed virtual robots)."""

    source: PoseSource
    sink: CommandSink

    def close(self) -> None:
        """Robots stopped first, then everything released (:func:`~swarmdeck.core.ports.close_ports`)."""
        from swarmdeck.core.ports import close_ports

        close_ports(self.source, self.sink)


def open_robots(spec: RobotsSpec) -> RobotPorts:
    """Open the robots ``spec`` describes (module docstring).

    Raises:
        ValueError, OSError: naming what could not be opened (a malformed URL, robots that sent no
            pose in time, a camera that cannot be read, too many robots for the arena); whatever
            was opened before is closed again.
    """
    from swarmdeck.devices.simulator import ArenaConfig

    arena = ArenaConfig(bounds=spec.bounds, dt=spec.dt, seed=spec.seed, obstacles=spec.obstacles)
    truth: Callable[[float], NDArray[np.float64]]
    if spec.robots_via is not None:
        net, _ = mqtt_robots(spec.robots_via, None if spec.n_robots is None else np.arange(spec.n_robots),
                             spec.wait_for_poses, partial=spec.partial)
        source: Any = net
        sink: Any = net
        truth = net.truth
    else:
        from swarmdeck.devices.simulated_robots import SimulatedRobots

        chargers = None
        if spec.docked or spec.chargers:
            from swarmdeck.devices.chargers import ChargerLayout

            chargers = ChargerLayout(bounds=spec.bounds)
            from swarmdeck.devices.fleet.routing import check_chargers_clear

            check_chargers_clear(arena.obstacles, chargers)
        sim = SimulatedRobots(int(spec.n_robots or 0), arena, spec.params, chargers=chargers,
                              start_docked=spec.docked, charge=spec.charge)
        source = sink = sim
        truth = sim.truth
    try:
        if spec.camera:
            ids = np.asarray(source.read(0.0).ids, dtype=np.int64)
            source = camera_source(spec.camera, ids, truth, spec.bounds)
        if spec.virtual:
            from swarmdeck.devices.virtual_robots import MixedRobots

            mixed = MixedRobots.add_virtual(source, sink, spec.virtual, arena, spec.params)
            source = sink = mixed
    except Exception:
        sink.close()
        raise
    return RobotPorts(source, sink)


def mqtt_robots(url: str, ids: NDArray[np.int64] | None, wait_for_poses: float = 5.0, *,
                partial: bool = False) -> tuple[NetworkRobots, NetworkRobots]:
    """The robots behind the broker at ``url`` (GRITSBots, or ``swarmdeck robots``) as (command sink,
    pose source): one ``NetworkRobots``, both ports (their pose topic; streamer watchdogs, obstacles
    for excluded robots). ``ids`` None: every robot heard of.

    Raises ValueError for a malformed URL or robots that sent no pose within ``wait_for_poses`` s.
    """
    from swarmdeck.devices.net.console_robots import NetworkRobots

    robots = NetworkRobots.connect(url, ids=ids, wait_for_poses=wait_for_poses, partial=partial)
    return robots, robots


def camera_source(spec: str, ids: NDArray[np.int64], truth: Callable[[float], NDArray[np.float64]] | None,
                  bounds: Bounds) -> TrackedPoseSource:
    """A tracked pose source for ``--camera`` ``synthetic`` (rendering ``truth(now)``), a webcam index,
    a stream URL, a folder of images or a video file. Raises ValueError naming what is wrong."""
    from swarmdeck.tracking import (
        CameraCalibration,
        CameraPoseSource,
        SyntheticCamera,
        SyntheticCameraConfig,
        TrackedPoseSource,
        Tracker,
        TrackerConfig,
        open_source,
    )

    expected = tuple(int(i) for i in ids)
    if spec == "synthetic":
        if truth is None:
            raise ValueError("--camera synthetic needs robots to render (the simulation or --robots-via)")
        cam = SyntheticCamera(truth, ids=expected, config=SyntheticCameraConfig(bounds=bounds))
        cal = CameraCalibration.from_camera(cam.renderer.camera)
        tracker = Tracker(TrackerConfig(calibration=cal, expected_ids=expected, bounds=bounds))
        return TrackedPoseSource(CameraPoseSource(cam, tracker), ids, "synthetic camera")
    src = open_source(spec)
    tracker = Tracker(TrackerConfig(expected_ids=expected, bounds=bounds))
    return TrackedPoseSource(CameraPoseSource(src, tracker), ids, f"camera {spec}")
