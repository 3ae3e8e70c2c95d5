"""The console-side command streamer and its watchdogs.

The control loop hands the streamer its latest safe commands
(:meth:`CommandStreamer.submit`); every :meth:`CommandStreamer.tick` sends one
command per robot through the transport, after three checks modelled on the
Robotarium's monitor node (REFERENCE.md §9):

* **stale poses** — a robot whose pose is older than ``pose_timeout`` (0.1 s) or
  was never seen gets zero: the command was computed from a position the
  robot may no longer be at;
* **stale inputs** — commands older than their timeout (``input_timeout``, or the
  ``valid_for`` given with them) give zero to every robot they name: the loop
  that produces them has stalled;
* **excluded robots** — robots the transport reports as missing (silent) or
  duplicated get zero and are listed by :meth:`CommandStreamer.obstacles` at
  their last known position, so the safety barrier can treat them as fixed
  obstacles (``SafetyFilter.filter(..., obstacles=(M, 2))``).

When the link is down nothing can be delivered: the streamer counts it and
reports it, and the robots brake by their own 500 ms timeout. Nothing here
raises into the caller's loop for bad input; problems are counted and described.
:meth:`CommandStreamer.start` runs :meth:`tick` in a background thread at a
fixed period, so zeros keep flowing even when the control loop itself hangs.
"""
from __future__ import annotations

import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.checks import require_positive
from swarmdeck.core.constants import CONTROL_PERIOD
from swarmdeck.core.service_thread import ServiceThread
from swarmdeck.devices.net.transport import Counters, ExcludesRobots, PoseFeed, RobotTransport, check_command

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


@dataclass(frozen=True)
class StreamerConfig:
    """Watchdog thresholds and the streaming period.

    Attributes:
        pose_timeout: poses older than this → zero command, s (Robotarium monitor: 0.1).
        input_timeout: submitted commands older than this → zero, s (unless ``valid_for`` says otherwise).
        period: background streaming period, s (the 30 Hz control period).
        max_events: how many recent watchdog events are kept for display.
    """

    pose_timeout: float = 0.1
    input_timeout: float = 0.1
    period: float = CONTROL_PERIOD
    max_events: int = 200

    def __post_init__(self) -> None:
        require_positive(self, ("pose_timeout", "input_timeout", "period"), "seconds")


@dataclass(frozen=True)
class StreamTick:
    """What one tick sent.

    Attributes:
        t: tick time, s (streamer clock).
        ids: ``(K,)`` robots commanded.
        v, w: ``(K,)`` commands as sent (after the watchdogs).
        stale_pose, stale_input, excluded: ``(K,)`` masks of robots zeroed for each reason.
        delivered: the transport accepted every command.
    """

    t: float
    ids: IntArray
    v: FloatArray
    w: FloatArray
    stale_pose: NDArray[np.bool_]
    stale_input: NDArray[np.bool_]
    excluded: NDArray[np.bool_]
    delivered: bool

    @property
    def zeroed(self) -> NDArray[np.bool_]:
        return self.stale_pose | self.stale_input | self.excluded


@dataclass
class _Input:
    ids: IntArray
    v: FloatArray
    w: FloatArray
    leds: NDArray[np.uint8] | None
    stamp: float
    valid_for: float


@dataclass(frozen=True)
class StreamerHealth:
    """For the console panel: link state, counts and recent events."""

    connected: bool
    state: str
    counters: dict[str, int]
    events: tuple[str, ...]
    excluded: IntArray = field(default_factory=lambda: np.empty(0, dtype=np.intp))


class CommandStreamer:
    """Streams the latest safe commands to the robots, zeroing whatever is unsafe to send.

    Args:
        transport: where commands go (:class:`~swarmdeck.devices.net.transport.RobotTransport`).
        poses: where the robots' poses come from (usually the transport itself); None skips
            the stale-pose check (in-process simulation, where poses are exact).
        config: thresholds and period.
        clock: monotonic clock shared with ``poses`` (receive stamps).
    """

    def __init__(
        self,
        transport: RobotTransport,
        poses: PoseFeed | None = None,
        config: StreamerConfig = StreamerConfig(),
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.transport = transport
        self.poses = poses
        self.config = config
        self.clock = clock
        self.counters = Counters()
        self.events: deque[str] = deque(maxlen=config.max_events)
        self._lock = threading.Lock()
        self._input: _Input | None = None
        self._prev_zeroed: dict[str, frozenset[int]] = {"stale_pose": frozenset(), "stale_input": frozenset(), "excluded": frozenset()}
        self._prev_delivered = True
        self._service = ServiceThread(self._run, "swarmdeck-streamer")
        self.last_tick: StreamTick | None = None
        self._tick_lock = threading.Lock()

    # ---------------------------------------------------------------- input side
    def submit(self, ids: ArrayLike, v: ArrayLike, w: ArrayLike, leds: ArrayLike | None = None,
               *, stamp: float | None = None, valid_for: float | None = None) -> None:
        """The control loop's latest commands: ``ids (K,)``, ``v, w (K,)``, optional LEDs.

        ``stamp`` is when they were computed (default: now); they are sent until
        ``valid_for`` s later (default ``input_timeout``), zero after that. Bad input
        (shapes, NaN, repeated ids) is counted and the affected robots get zero.
        """
        cmd = check_command(ids, v, w, leds)
        for p in cmd.problems:
            self.counters.add("bad_input", p)
            self._event(p)
        t = self.clock() if stamp is None else float(stamp)
        vf = self.config.input_timeout if valid_for is None else float(valid_for)
        if not (np.isfinite(vf) and vf > 0):
            self.counters.add("bad_input", f"valid_for must be a positive number of seconds, got {valid_for!r}: using 0")
            vf = 0.0
        with self._lock:
            self._input = _Input(cmd.ids, cmd.v, cmd.w, cmd.leds, t, vf)

    # ---------------------------------------------------------------- one tick
    def tick(self, now: float | None = None) -> StreamTick:
        """Apply the watchdogs to the latest input and send one command per robot (thread-safe)."""
        with self._tick_lock:
            return self._tick(now)

    def _tick(self, now: float | None) -> StreamTick:
        now = self.clock() if now is None else float(now)
        with self._lock:
            inp = self._input
        if inp is None:
            empty = np.empty(0)
            nob = np.zeros(0, dtype=bool)
            tick = StreamTick(now, np.empty(0, dtype=np.intp), empty, empty, nob, nob, nob, True)
            self.last_tick = tick
            return tick
        ids = inp.ids
        k = len(ids)
        stale_input = np.full(k, now - inp.stamp > inp.valid_for)
        stale_pose = np.zeros(k, dtype=bool)
        if self.poses is not None:
            try:
                sample = self.poses.latest_poses()
                _, stamps = sample.select(ids)
                stale_pose = (now - stamps) > self.config.pose_timeout
            except Exception as exc:  # noqa: BLE001 - a broken pose source stops the robots, not the loop
                self.counters.add("pose_source_errors", f"pose source failed: {exc!r}: all robots stopped")
                stale_pose = np.ones(k, dtype=bool)
        excluded = np.zeros(k, dtype=bool)
        if isinstance(self.transport, ExcludesRobots):
            try:
                excluded = np.isin(ids, np.asarray(self.transport.excluded(), dtype=np.intp))
            except Exception as exc:  # noqa: BLE001
                self.counters.add("transport_errors", f"transport.excluded() failed: {exc!r}")
        zero = stale_pose | stale_input | excluded
        v = np.where(zero, 0.0, inp.v)
        w = np.where(zero, 0.0, inp.w)
        try:
            delivered = bool(self.transport.send(ids, v, w, inp.leds))
        except Exception as exc:  # noqa: BLE001 - transports should not raise; if one does, count it
            self.counters.add("transport_errors", f"transport.send failed: {exc!r}")
            delivered = False
        self._account(now, ids, stale_pose, stale_input, excluded, delivered)
        tick = StreamTick(now, ids, v, w, stale_pose, stale_input, excluded, delivered)
        self.last_tick = tick
        return tick

    def _account(self, now: float, ids: IntArray, stale_pose: NDArray[np.bool_], stale_input: NDArray[np.bool_],
                 excluded: NDArray[np.bool_], delivered: bool) -> None:
        labels = {
            "stale_pose": (f"pose older than {self.config.pose_timeout:.2f} s: commanded to zero", "poses fresh again"),
            "stale_input": ("commands older than their timeout: commanded to zero", "commands fresh again"),
            "excluded": ("missing or duplicated: excluded from control (fixed obstacle at last known position)",
                         "answering again: back under control"),
        }
        for name, mask in (("stale_pose", stale_pose), ("stale_input", stale_input), ("excluded", excluded)):
            n = int(mask.sum())
            if n:
                self.counters.add(f"{name}_robot_ticks", n=n)
            cur = frozenset(ids[mask].tolist())
            prev = self._prev_zeroed[name]
            on, off = sorted(cur - prev), sorted(prev - cur)
            if on:
                self._event(f"t={now:.3f}: robot(s) {on}: {labels[name][0]}")
            if off:
                self._event(f"t={now:.3f}: robot(s) {off}: {labels[name][1]}")
            self._prev_zeroed[name] = cur
        if not delivered:
            self.counters.add("undelivered_ticks")
        if delivered != self._prev_delivered:
            self._event(f"t={now:.3f}: " + ("commands delivered again" if delivered else
                                             "commands cannot be delivered; robots stop by their 500 ms timeout"))
            self._prev_delivered = delivered
        self.counters.add("ticks")

    def _event(self, text: str) -> None:
        self.events.append(text)

    # ---------------------------------------------------------------- views
    def obstacles(self) -> FloatArray:
        """``(M, 2)`` last known centres of the excluded robots (fixed obstacles for the barrier), m."""
        if not isinstance(self.transport, ExcludesRobots) or self.poses is None:
            return np.empty((0, 2))
        ids = np.asarray(self.transport.excluded(), dtype=np.intp)
        if not len(ids):
            return np.empty((0, 2))
        poses, _ = self.poses.latest_poses().select(ids)
        known = np.all(np.isfinite(poses), axis=1)
        return poses[known, :2].copy()

    def health(self) -> StreamerHealth:
        st = self.transport.status()
        excluded = (np.asarray(self.transport.excluded(), dtype=np.intp) if isinstance(self.transport, ExcludesRobots)
                    else np.empty(0, dtype=np.intp))
        counters = dict(st.counters)
        counters.update({f"streamer_{k}": v for k, v in self.counters.snapshot().items()})
        return StreamerHealth(st.connected, st.state, counters, tuple(self.events), excluded)

    # ---------------------------------------------------------------- background streaming
    def start(self) -> CommandStreamer:
        """Keep commands flowing from a background thread until :meth:`stop`.

        The thread ticks whenever no tick happened for ``period`` s, so a loop that calls
        :meth:`tick` itself right after :meth:`submit` sees no added latency, and a loop
        that hangs still has its robots zeroed (stale input) at the streaming rate.
        """
        self._service.start()
        return self

    def _run(self) -> None:
        period = self.config.period
        nxt = self.clock()
        svc = self._service
        while not svc.stopping:
            last = self.last_tick
            if last is None or self.clock() - last.t >= 0.9 * period:
                try:
                    self.tick()
                except Exception as exc:  # noqa: BLE001 - the streaming thread must survive anything
                    self.counters.add("tick_errors", f"tick failed: {exc!r}")
            nxt += period
            delay = nxt - self.clock()
            if delay > 0:
                svc.wait(delay)
            else:
                nxt = self.clock()

    def stop(self) -> None:
        """Stop background streaming and send one zero command to the last robots named."""
        self._service.stop()
        with self._lock:
            inp = self._input
        if inp is not None and len(inp.ids):
            try:
                self.transport.send(inp.ids, np.zeros(len(inp.ids)), np.zeros(len(inp.ids)))
            except Exception as exc:  # noqa: BLE001
                self.counters.add("transport_errors", f"final stop command failed: {exc!r}")
