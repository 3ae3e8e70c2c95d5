"""The one robot-transport interface: commands out, robot status and poses in.

A transport moves one unicycle command per robot per control tick to the
robots and brings back what they report. Implementations:

* :class:`~swarmdeck.devices.net.transport_inprocess.InProcessTransport` — the
  simulated arena in this process (the default: no broker, no sockets);
* :class:`~swarmdeck.devices.net.transport_mqtt.MqttTransport` — GRITSBot X robots
  (real, or the simulated fleet of ``swarmdeck robots``) over an MQTT broker,
  in the wire format of REFERENCE.md §9.

Both are also a :class:`PoseFeed`: stamped tracker-style pose samples (the
simulator's ground truth, or ``overhead_tracker/all_robot_pose_data``) whose
freshness the command streamer's watchdogs judge on the receiver's clock. The
control loop does not read these directly: ``NetworkRobots`` turns them into
the loop's ``PoseSource`` / ``CommandSink`` ports (:mod:`swarmdeck.core.ports`,
which describes the whole vocabulary).

Arrays follow the shared convention: one row per robot; ids are small
non-negative ints; v in m/s, ω in rad/s, LED colours ``(N, 3)`` ints 0–255.
"""
from __future__ import annotations

import threading
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

IntArray = NDArray[np.intp]
FloatArray = NDArray[np.float64]

#: Link states of one robot as seen from the console side.
LINK_OK = "ok"  # status and poses arrive, commands are delivered
LINK_STALE = "stale"  # pose older than the streamer's pose timeout: commanded to zero
LINK_MISSING = "missing"  # nothing heard for the missing timeout: excluded from control
LINK_UNKNOWN = "unknown"  # never heard of


@dataclass(frozen=True)
class PoseSample:
    """Latest tracker-style poses, one row per robot that was ever seen.

    Attributes:
        ids: ``(N,)`` robot ids, ascending.
        poses: ``(N, 3)`` ``[x, y, θ]`` in m, rad (the last known pose of each).
        stamps: ``(N,)`` receive time of each row on the receiver's monotonic clock, s.
    """

    ids: IntArray
    poses: FloatArray
    stamps: FloatArray

    @staticmethod
    def empty() -> PoseSample:
        return PoseSample(np.empty(0, dtype=np.intp), np.empty((0, 3)), np.empty(0))

    def ages(self, now: float) -> FloatArray:
        """``(N,)`` seconds since each row was received."""
        return now - self.stamps

    def select(self, ids: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Poses ``(K, 3)`` and stamps ``(K,)`` for ``ids``; rows never seen are NaN / -inf."""
        want = np.asarray(ids, dtype=np.intp).reshape(-1)
        poses = np.full((len(want), 3), np.nan)
        stamps = np.full(len(want), -np.inf)
        if len(self.ids) and len(want):
            pos = np.searchsorted(self.ids, want)
            pos_c = np.minimum(pos, len(self.ids) - 1)
            hit = self.ids[pos_c] == want
            poses[hit] = self.poses[pos_c[hit]]
            stamps[hit] = self.stamps[pos_c[hit]]
        return poses, stamps


@dataclass(frozen=True)
class RobotStatusTable:
    """What the robots last reported, one row per robot known to the transport.

    Attributes:
        ids: ``(N,)`` robot ids, ascending.
        battery_voltage: ``(N,)`` V (NaN: never reported).
        charging: ``(N,)`` bool.
        command_age: ``(N,)`` s since the robot last received a command, now: its reported
            age plus the age of the report (NaN: robot does not report it; inf: never commanded).
        status_age: ``(N,)`` s since the last status message arrived (inf: never).
        link: per robot one of ``ok``, ``stale``, ``missing``, ``unknown``.
    """

    ids: IntArray
    battery_voltage: FloatArray
    charging: NDArray[np.bool_]
    command_age: FloatArray
    status_age: FloatArray
    link: tuple[str, ...]

    def battery_of(self, ids: ArrayLike) -> tuple[FloatArray, NDArray[np.bool_]]:
        """Battery voltages ``(K,)`` V and charging flags ``(K,)`` of ``ids`` (NaN / False for robots
        this table does not hold)."""
        want = np.asarray(ids, dtype=np.intp).reshape(-1)
        volts, charging = np.full(len(want), np.nan), np.zeros(len(want), dtype=bool)
        if len(self.ids) and len(want):
            pos = np.minimum(np.searchsorted(self.ids, want), len(self.ids) - 1)
            hit = self.ids[pos] == want
            volts[hit], charging[hit] = self.battery_voltage[pos[hit]], self.charging[pos[hit]]
        return volts, charging

    @staticmethod
    def empty() -> RobotStatusTable:
        return RobotStatusTable(np.empty(0, dtype=np.intp), np.empty(0), np.zeros(0, bool), np.empty(0), np.empty(0), ())

    def to_dict(self) -> dict:
        """JSON-able ``{"<id>": {...}}`` (NaN/inf become None)."""

        def num(x: float) -> float | None:
            return float(x) if np.isfinite(x) else None

        return {
            str(int(i)): {
                "battery_voltage": num(self.battery_voltage[k]),
                "charging": bool(self.charging[k]),
                "command_age": num(self.command_age[k]),
                "status_age": num(self.status_age[k]),
                "link": self.link[k],
            }
            for k, i in enumerate(self.ids)
        }


@dataclass(frozen=True)
class TransportStatus:
    """Health of a transport and of every robot behind it.

    Attributes:
        connected: True when commands can currently be delivered.
        state: one-line human-readable state ("connected to mqtt://…", "reconnecting in 0.4 s …").
        robots: per-robot status.
        counters: running counts of events and bad input by name (e.g. ``malformed_status``).
        last_error: the most recent problem, as a clear sentence, or None.
    """

    connected: bool
    state: str
    robots: RobotStatusTable
    counters: Mapping[str, int] = field(default_factory=dict)
    last_error: str | None = None

    def to_dict(self) -> dict:
        return {
            "connected": self.connected,
            "state": self.state,
            "robots": self.robots.to_dict(),
            "counters": dict(self.counters),
            "last_error": self.last_error,
        }


@runtime_checkable
class RobotTransport(Protocol):
    """Carries unicycle commands to robots and their status back (the wire)."""

    def send(self, ids: ArrayLike, v: ArrayLike, w: ArrayLike, leds: ArrayLike | None = None) -> bool:
        """Send one command per robot: ``ids (K,)``, ``v (K,)`` m/s, ``w (K,)`` rad/s,
        ``leds`` None or ``(K, 2, 3)`` / ``(K, 3)`` RGB 0–255 (left, right).

        Never raises for bad input or a broken link: robots whose command is
        invalid get zero, problems are counted in :meth:`status`. Returns True when
        every command was handed to the link.
        """

    def status(self) -> TransportStatus:
        """Link health and the latest report of every robot."""

    def robots(self) -> IntArray:
        """Ids of the robots present (reporting status or poses recently), ascending."""

    def close(self) -> None:
        """Stop the robots where possible and release the link."""


@runtime_checkable
class ExcludesRobots(Protocol):
    """A transport that takes robots out of control (missing or duplicated in the poses): the streamer sends them
    zero and the barrier keeps them as fixed obstacles."""

    def excluded(self) -> ArrayLike:
        """Ids of the robots excluded now."""


@runtime_checkable
class PoseFeed(Protocol):
    """Stamped tracker-style poses as received (the wire side; the loop's port is ``core.ports.PoseSource``)."""

    def latest_poses(self) -> PoseSample:
        """The newest pose of every robot seen so far, with receive stamps."""


@dataclass(frozen=True)
class CheckedCommand:
    """A command batch after validation: always safe to send.

    Attributes:
        ids, v, w: ``(K,)`` arrays (invalid entries replaced by zero speed).
        leds: ``(K, 2, 3)`` uint8 or None.
        problems: clear messages for everything that was wrong (empty when fine).
        zeroed: ``(K,)`` mask of robots whose command was replaced by zero.
    """

    ids: IntArray
    v: FloatArray
    w: FloatArray
    leds: NDArray[np.uint8] | None
    problems: tuple[str, ...]
    zeroed: NDArray[np.bool_]


def _real_array(x: object) -> FloatArray:
    """``x`` as a float array, or an empty ``(0,)`` array when it is not real numbers (text, complex, ragged)."""
    try:
        arr = np.asarray(x)
        if arr.dtype.kind not in "fiub":
            return np.empty(0)
        return arr.astype(float)
    except (TypeError, ValueError):
        return np.empty(0)


def _shape(x: Any) -> object:
    try:
        return np.shape(x)
    except (TypeError, ValueError):
        return "ragged"


def check_command(ids: ArrayLike, v: ArrayLike, w: ArrayLike, leds: ArrayLike | None = None) -> CheckedCommand:
    """Validate one command batch without raising.

    * ids must be non-negative integers; negative or non-integer ids are dropped;
      a repeated id keeps only its first entry and is zeroed (which command was meant
      is ambiguous: the robot is stopped);
    * v, w must have one finite entry per id, otherwise the affected robots get zero
      (a length mismatch zeroes every robot);
    * leds: ``(K, 3)`` (both LEDs) or ``(K, 2, 3)``, clipped to 0–255; a bad shape drops
      the LEDs for this batch (speeds are still sent).
    """
    problems: list[str] = []
    raw_ids = np.asarray(ids).reshape(-1)
    if raw_ids.dtype.kind not in "iu":
        as_float = np.asarray(raw_ids, dtype=float) if raw_ids.dtype.kind == "f" else None
        if as_float is None or not np.all(np.isfinite(as_float)) or not np.all(as_float == np.round(as_float)):
            problems.append(f"robot ids must be integers, got dtype {raw_ids.dtype}: batch dropped")
            empty = np.empty(0)
            return CheckedCommand(np.empty(0, np.intp), empty, empty, None, tuple(problems), np.zeros(0, bool))
        raw_ids = as_float.astype(np.int64)
    k = len(raw_ids)
    v_arr, w_arr = _real_array(v).reshape(-1), _real_array(w).reshape(-1)
    zeroed = np.zeros(k, dtype=bool)
    if v_arr.shape != (k,) or w_arr.shape != (k,):
        problems.append(f"v and w must be real numbers with shape ({k},) like ids, got {_shape(v)} and "
                        f"{_shape(w)}: all robots stopped")
        v_arr, w_arr = np.zeros(k), np.zeros(k)
        zeroed[:] = True
    bad = ~(np.isfinite(v_arr) & np.isfinite(w_arr))
    if bad.any():
        problems.append(f"non-finite command for robot(s) {raw_ids[bad].tolist()}: stopped")
        zeroed |= bad
    keep = raw_ids >= 0
    if not keep.all():
        problems.append(f"negative robot id(s) {raw_ids[~keep].tolist()} dropped")
    _, first = np.unique(raw_ids, return_index=True)
    is_first = np.zeros(k, dtype=bool)
    is_first[first] = True
    if not is_first.all():
        dup = np.unique(raw_ids[~is_first])
        problems.append(f"duplicate robot id(s) {dup.tolist()} in one command batch: those robots stopped")
        zeroed |= np.isin(raw_ids, dup)
    keep &= is_first
    v_out = np.where(zeroed, 0.0, v_arr)[keep]
    w_out = np.where(zeroed, 0.0, w_arr)[keep]
    led_out: NDArray[np.uint8] | None = None
    if leds is not None:
        arr = _real_array(leds)
        if arr.shape == (k, 3):
            arr = np.repeat(arr[:, None, :], 2, axis=1)
        if arr.shape == (k, 2, 3) and np.all(np.isfinite(arr)):
            led_out = np.clip(np.rint(arr), 0, 255).astype(np.uint8)[keep]
        else:
            problems.append(f"leds must be finite numbers with shape ({k}, 3) or ({k}, 2, 3), got shape "
                            f"{_shape(leds)}: LEDs not sent")
    return CheckedCommand(raw_ids[keep].astype(np.intp), v_out, w_out, led_out, tuple(problems), zeroed[keep])


class Counters:
    """Named event counts, thread-safe, with the most recent problem message."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._counts: dict[str, int] = {}
        self.last_error: str | None = None

    def add(self, name: str, message: str | None = None, n: int = 1) -> None:
        with self._lock:
            self._counts[name] = self._counts.get(name, 0) + n
            if message is not None:
                self.last_error = message

    def snapshot(self) -> dict[str, int]:
        with self._lock:
            return dict(self._counts)

    def get(self, name: str) -> int:
        with self._lock:
            return self._counts.get(name, 0)
