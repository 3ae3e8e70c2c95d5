"""A :class:`~swarmdeck.devices.backend.RobotBackend` that drives robots through a transport.

The experiment API (:class:`~swarmdeck.devices.arena.Arena`) calls
``backend.poses`` and ``backend.step(v, w)``; here poses come from a
tracker-style :class:`~swarmdeck.devices.net.transport.PoseFeed` (the MQTT pose
topic, i.e. the simulated fleet's ground truth or a real tracker) and commands
go out through a :class:`~swarmdeck.devices.net.streamer.CommandStreamer`, so its
watchdogs apply to every step. ``step`` paces itself to real time (one
``dt`` per call), as real robots require.

Example (with ``swarmdeck robots --broker mqtt://127.0.0.1:1883 --robots 6`` running)::

    from swarmdeck.devices import Arena
    from swarmdeck.devices.net.transport_backend import mqtt_backend
    backend = mqtt_backend("mqtt://127.0.0.1:1883", n_robots=6)
    arena = Arena(backend=backend)
"""
from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.kinematics import GritsBotParams, limit_unicycle
from swarmdeck.devices.clock import RealTimePacer
from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.net.streamer import CommandStreamer, StreamerConfig
from swarmdeck.devices.net.transport import PoseFeed, RobotTransport
from swarmdeck.devices.net.transport_mqtt import MqttTransport

FloatArray = NDArray[np.float64]


class TransportBackend:
    """Robots ``ids`` behind ``transport``, with poses from ``poses`` (default: the transport).

    Args:
        transport: a started transport.
        ids: ``(N,)`` robot ids; row k of every array is robot ``ids[k]``.
        poses: pose feed (default: ``transport`` itself, which must then be a PoseFeed).
        params: robot model (for the Arena's look-ahead and limits).
        dt: control period, s.
        streamer: watchdog thresholds.
        clock: monotonic clock shared with the transport.
        wait_for_poses: s to wait for a first pose of every robot before giving up.
        real_time: pace ``step`` to one ``dt`` of wall time.

    Raises:
        ValueError: some robots sent no pose within ``wait_for_poses`` (named in the message).
    """

    def __init__(
        self,
        transport: RobotTransport,
        ids: ArrayLike,
        *,
        poses: PoseFeed | None = None,
        params: GritsBotParams = GritsBotParams(),
        dt: float = 0.033,
        streamer: StreamerConfig | None = None,
        clock: Callable[[], float] = time.monotonic,
        wait_for_poses: float = 5.0,
        real_time: bool = True,
    ) -> None:
        self.transport = transport
        self.ids = np.asarray(ids, dtype=np.intp).reshape(-1).copy()
        if not len(self.ids) or len(np.unique(self.ids)) != len(self.ids) or np.any(self.ids < 0):
            raise ValueError(f"ids must be distinct non-negative integers, got {self.ids.tolist()}")
        self.n_robots = len(self.ids)
        self.params = params
        self.dt = float(dt)
        self.clock = clock
        src = poses if poses is not None else transport
        if not callable(getattr(src, "latest_poses", None)):
            raise ValueError("the transport gives no poses: pass poses=<a PoseFeed>")
        self.pose_feed: PoseFeed = src  # type: ignore[assignment]
        cfg = streamer if streamer is not None else StreamerConfig(period=self.dt)
        self.streamer = CommandStreamer(transport, self.pose_feed, cfg, clock)
        self._pacer = RealTimePacer(self.dt) if real_time else None
        deadline = clock() + wait_for_poses
        while True:
            p, _ = self.pose_feed.latest_poses().select(self.ids)
            missing = self.ids[~np.all(np.isfinite(p), axis=1)]
            if not len(missing):
                break
            if clock() >= deadline:
                state = transport.status().state
                raise ValueError(
                    f"no pose received for robot id(s) {missing.tolist()} within {wait_for_poses} s ({state}); "
                    "is `swarmdeck robots` (or the tracker) running with these ids?"
                )
            time.sleep(0.02)
        self._last = p
        self._t0 = clock()
        self.saturated = 0  # robot-steps whose command the wheel limits scaled down
        self.invalid = 0  # robot-steps whose command was NaN/inf (sent as zero)

    @property
    def poses(self) -> FloatArray:
        """Latest pose of every robot ``(N, 3)`` (last known for robots gone silent)."""
        p, _ = self.pose_feed.latest_poses().select(self.ids)
        ok = np.all(np.isfinite(p), axis=1)
        self._last = np.where(ok[:, None], p, self._last)
        return self._last.copy()

    @property
    def time(self) -> float:
        """Seconds since this backend was created (monotonic clock)."""
        return self.clock() - self._t0

    def step(self, v: ArrayLike, w: ArrayLike) -> FloatArray:
        """Send ``(v, ω)`` ``(N,)`` through the watchdogs, wait one period, return the new poses.

        As on the simulated arena, non-finite commands become zero and the wheel limits are applied
        by one uniform scale per robot (curvature kept) before anything is sent: real firmware clips
        each wheel on its own, which would change the direction of motion. ``saturated`` counts the
        robot-steps scaled down, ``invalid`` the non-finite ones.
        """
        v = np.asarray(v, dtype=float).reshape(-1)
        w = np.asarray(w, dtype=float).reshape(-1)
        if v.shape != (self.n_robots,) or w.shape != (self.n_robots,):
            raise ValueError(f"v and w must each have shape ({self.n_robots},), got {v.shape} and {w.shape}")
        bad = ~(np.isfinite(v) & np.isfinite(w))
        v, w, saturated = limit_unicycle(np.where(bad, 0.0, v), np.where(bad, 0.0, w), self.params)
        self.saturated += int(saturated.sum())
        self.invalid += int(bad.sum())
        self.streamer.submit(self.ids, v, w, valid_for=max(3 * self.dt, self.streamer.config.input_timeout))
        self.streamer.tick()
        if self._pacer is not None:
            self._pacer.wait()
        return self.poses

    def obstacles(self) -> FloatArray:
        """Last known centres ``(M, 2)`` of robots excluded from control."""
        return self.streamer.obstacles()

    def close(self) -> None:
        """Stop the robots and close the transport."""
        self.streamer.stop()
        self.transport.close()


def mqtt_backend(url: str, n_robots: int | None = None, ids: ArrayLike | None = None, **kwargs: object) -> TransportBackend:
    """Connect to ``url`` (``mqtt://HOST:PORT``) and drive robots ``ids`` (default ``0..n_robots-1``).

    Extra keyword arguments go to :class:`TransportBackend` (``dt``, ``wait_for_poses``, …).
    """
    if ids is None:
        if n_robots is None:
            raise ValueError("give n_robots or ids")
        ids = np.arange(int(n_robots))
    transport = MqttTransport(parse_broker_url(url), ids=ids).start()
    try:
        return TransportBackend(transport, ids, **kwargs)  # type: ignore[arg-type]
    except Exception:
        transport.close()
        raise
