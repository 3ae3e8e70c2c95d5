"""The robot ports: how poses come in and commands go out (DESIGN.md "One tick", steps 1 and 5).

One name per concept, for every kind of robot (the simulator, the overhead
camera, GRITSBots over MQTT, the in-process transport):

* :class:`SensedPoses` — one reading: ids ``(N,)``, poses ``(N, 3)``
  ``[x, y, θ]`` (m, rad), ``seen`` ``(N,)`` (a fresh pose this tick; robots not
  seen get zero commands and are fixed obstacles of the barrier), and, where the
  source knows them, ``is_virtual`` ``(N,)`` (simulated beside physical robots,
  ``devices.virtual_robots``), ``battery`` ``(N,)`` V (NaN: unknown) and
  ``charging`` ``(N,)`` (REFERENCE.md §9 ``batt_volt``/``charge_status``).
* :class:`PoseSource` — what the control loop reads once per tick:
  ``read(now) -> SensedPoses``, ``health() -> str``, ``name``. Implemented by
  ``devices.simulated_robots.SimulatedRobots`` (the simulator's truth),
  ``tracking.TrackedPoseSource`` (camera → ArUco → homography), and
  ``devices.net.console_robots.NetworkRobots`` (the robots' MQTT pose topic).
* :class:`CommandSink` — where the control loop sends one unicycle command
  ``(v m/s, ω rad/s)`` per robot id each tick: ``send``, ``hold`` (paused),
  ``health``, ``close``, optionally ``obstacles() -> (M, 2)`` (robots excluded
  from control, for the barrier). Implemented by ``SimulatedRobots`` and
  ``NetworkRobots`` (any ``RobotTransport`` behind the streamer's watchdogs).

These two ports are the only robot interface: the console loop reads and sends through them,
and so does the experiment API — ``devices.arena.Arena`` drives any ports through one adapter,
``devices.stepped.SteppedRobots`` (``poses``, ``time``, ``step(v, w)`` one period at a time). A
simulation says how much simulated time a reading is at (``SensedPoses.time``); robots in the real
world leave it None and the adapter paces them to the period on the monotonic clock. A sink behind
a trust boundary (the sandboxed script's robots, ``console/sandbox/child.py``) is a
:class:`NominalSink`: it takes the nominal look-ahead velocities and the far side certifies them.

The wire below the ports keeps its own name: ``devices.net.transport.RobotTransport`` carries
commands (with LEDs) to robots and brings back their status and stamped pose samples
(``PoseFeed.latest_poses() -> PoseSample``, judged for staleness by the command streamer on the
receiver's clock). Implemented by ``MqttTransport`` and ``InProcessTransport``; everything above it
reaches it only through ``NetworkRobots``.

This module is at the bottom of the dependency graph so that every subsystem
(``tracking`` included, which imports nothing above ``core``) can speak it.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol, cast, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray


@dataclass(frozen=True)
class SensedPoses:
    """One reading: ids (N,) int, poses (N, 3) [x, y, θ] (m, rad), seen (N,) bool (fresh this tick);
    optional is_virtual (N,) bool (None: all physical), battery (N,) V (None or NaN: unknown),
    charging (N,) bool (None: unknown) and time, s: the robots' simulated clock at this reading
    (None: robots in the real world, on the reader's monotonic clock)."""

    ids: NDArray[np.int64]
    poses: NDArray[np.float64]
    seen: NDArray[np.bool_]
    is_virtual: NDArray[np.bool_] | None = None
    battery: NDArray[np.float64] | None = None
    charging: NDArray[np.bool_] | None = None
    time: float | None = None


@runtime_checkable
class PoseSource(Protocol):
    """Where the control loop's poses come from, once per tick."""

    name: str

    def read(self, now: float) -> SensedPoses:
        """The robots' poses at loop time ``now`` (s)."""

    def health(self) -> str:
        """One short line for the status bar."""


@runtime_checkable
class CommandSink(Protocol):
    """Where the control loop's commands go, once per tick."""

    name: str

    def send(self, ids: NDArray[np.int64], v: NDArray[np.float64], w: NDArray[np.float64]) -> None:
        """Apply / transmit (v m/s, ω rad/s) for the given robot ids (one period)."""

    def hold(self) -> None:
        """Paused: robots stand still (a simulation does not advance)."""

    def health(self) -> str:
        """One short line for the status bar."""

    def close(self) -> None:
        """Stop the robots and release resources."""


@runtime_checkable
class NominalSink(Protocol):
    """A command sink behind a trust boundary: it takes the nominal look-ahead velocities before any
    limit or filter, and the far side (which owns the robots) certifies them."""

    def send_nominal(self, ids: NDArray[np.int64], nominal: NDArray[np.float64]) -> None:
        """Hand over the nominal ``(N, 2)`` look-ahead velocities (m/s) for ``ids`` (one period)."""


def rows_of(ids: ArrayLike, want: ArrayLike) -> tuple[NDArray[np.intp], NDArray[np.bool_]]:
    """Rows ``(K,)`` of the robot ids ``want`` in ``ids`` ``(N,)`` and whether each is there (rows of
    missing ids are 0, not to be used)."""
    ids = np.asarray(ids, dtype=np.int64).reshape(-1)
    want = np.asarray(want, dtype=np.int64).reshape(-1)
    if not len(ids):
        return np.zeros(len(want), dtype=np.intp), np.zeros(len(want), dtype=bool)
    order = np.argsort(ids)
    rows = order[np.minimum(np.searchsorted(ids[order], want), len(ids) - 1)]
    present = ids[rows] == want
    return np.where(present, rows, 0).astype(np.intp), present


def close_ports(source: PoseSource, sink: CommandSink) -> None:
    """Close the sink (robots stopped first), then the source unless it is the same object.

    A source without ``close`` is left alone; the source is closed even when closing the sink raises.
    """
    try:
        sink.close()
    finally:
        if source is not cast(object, sink) and isinstance(source, Closeable):
            source.close()


# Optional capabilities of a pose source, command sink or backend: checked with isinstance (runtime_checkable),
# never with getattr, so each is named and typed once here.

@runtime_checkable
class Closeable(Protocol):
    """Holds resources (sockets, threads, a camera) to release."""

    def close(self) -> None: ...


@runtime_checkable
class ReportsObstacles(Protocol):
    """Holds robots out of control (missing, duplicated or docked) and says where they stand, so the barrier keeps
    them as fixed points."""

    def obstacles(self) -> NDArray[np.float64] | None:
        """Their last known positions ``(M, 2)``, m (None or no rows: none)."""


@runtime_checkable
class ReportsRobotHealth(Protocol):
    """Talks to robot firmware that reports its own status (``NetworkRobots``)."""

    def robot_health(self) -> dict[str, dict[str, Any]]:
        """Robot id (as text) → its last status report (``status_age`` s, battery, …)."""


@runtime_checkable
class ProvidesImage(Protocol):
    """A pose source that also has the camera images its poses came from (``CameraPoseSource``)."""

    @property
    def image_ref(self) -> str | None:
        """A reference to this tick's image (None: no image yet)."""

    def image(self, ref: str) -> tuple[NDArray[Any], tuple[float, float, float, float]] | None:
        """The image for ``ref`` and the floor rectangle it shows ``(x_min, x_max, y_min, y_max)``, m."""


@runtime_checkable
class ReportsValidation(Protocol):
    """Validates the commands it is given and counts what it found (the simulator's ``ValidationReport``)."""

    @property
    def report(self) -> Any:
        """The validation report so far (None: not validating)."""


@runtime_checkable
class ReportsSensors(Protocol):
    """Robots whose firmware reports what their own sensors read (ToF distances, encoders, IMU; issue 28.1): the
    experiment API hands these readings out instead of simulating them."""

    def sensor_readings(self) -> Any:
        """The latest readings as a ``swarmdeck.sensing.SensorReadings`` (rows in the port's robot order), or None
        when the robots reported none yet (the Arena then simulates them from the poses)."""


@runtime_checkable
class ShowsLeds(Protocol):
    """Robots with an RGB LED the experiment can set (GRITSBots: carried with the commands; issue 28.1)."""

    def set_leds(self, ids: NDArray[np.int64], rgb: NDArray[np.uint8]) -> None:
        """Show ``rgb`` ``(K, 3)`` (0…255) on robots ``ids`` ``(K,)`` from the next command on, until set again."""


@runtime_checkable
class SensesElsewhere(Protocol):
    """Robots whose sensors are simulated on the far side of a trust boundary (the sandbox's trusted side, issue 28):
    the Arena tells them which sensors the experiment uses, and takes their readings (:class:`ReportsSensors`)."""

    def use_sensors(self, config: Any) -> None:
        """The experiment's ``swarmdeck.sensing.SensingConfig`` from now on (None: no sensors)."""


def obstacles_of(port: object) -> NDArray[np.float64] | None:
    """``port.obstacles()`` when ``port`` reports obstacles (:class:`ReportsObstacles`), else None."""
    return port.obstacles() if isinstance(port, ReportsObstacles) else None
