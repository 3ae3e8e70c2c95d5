"""Live Foxglove: the loop's Frames served over the Foxglove WebSocket protocol (``swarmdeck console --foxglove``).

:class:`FoxgloveBridge` subscribes to the control loop's Frames like the viser
scene does (the loop thread only stores the Frame and wakes the bridge) and, on
its own thread, encodes them with the recorder's
:class:`~swarmdeck.console.recording.foxglove.FoxgloveEncoder` into the same
channels a recording carries, logged through the official ``foxglove-sdk``
WebSocket server (``foxglove.start_server``, its own ``foxglove.Context``) on a
private loopback port, behind :class:`~swarmdeck.console.web.ws_relay.SubprotocolRelay`
on the public one, so clients asking for either name of the protocol,
``foxglove.sdk.v1`` (the SDK's) or ``foxglove.websocket.v1`` (the official
``@foxglove/ws-protocol`` client's, older Foxglove apps', Lichtblick's), connect.
In Foxglove: *Open connection → Foxglove WebSocket → ws://127.0.0.1:8765*, then
import the shipped layout (``swarmdeck foxglove-layout``).

When the bridge falls behind, it draws only the newest Frame (latest wins, as
the viser viewer does) but still sends the events of the Frames it skipped to
the Log channel. It binds 127.0.0.1 unless told otherwise; a port in use is a
:class:`FoxglovePortInUse` at construction, before the loop starts.
"""
from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

from swarmdeck.console.recording.foxglove import (
    TOPIC_LOG,
    FoxgloveConfig,
    FoxgloveEncoder,
    channel_specs,
)
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.core.bounds import Bounds
from swarmdeck.core.constants import ROBOT_RADIUS
from swarmdeck.core.errors import SwarmdeckError
from swarmdeck.core.service_thread import ServiceThread

DEFAULT_PORT = 8765


class FoxglovePortInUse(OSError, SwarmdeckError):
    """The Foxglove WebSocket server could not bind its port."""


class FoxgloveBridge:
    """Serve a loop's Frames to Foxglove over WebSocket.

    Args:
        bounds: arena rectangle (x_min, x_max, y_min, y_max), m.
        host: interface to bind (127.0.0.1: this machine only).
        port: TCP port (0 picks a free one; see :attr:`port`).
        robot_radius: disc radius, m.
        config: :class:`FoxgloveConfig` (density and camera rates; default
            :meth:`FoxgloveConfig.per_entity`: live there is no file to keep small, so a disc, an arrow and a
            label per robot every frame up to 100 robots; a packed config is served packed).
        image_provider: the camera source's ``image(ref)``, when a camera runs.

    Use: ``bridge = FoxgloveBridge(bounds); unsubscribe = loop.subscribe(bridge.offer); bridge.start()``;
    ``bridge.close()`` at exit.
    """

    def __init__(self, bounds: Bounds, host: str = "127.0.0.1", port: int = DEFAULT_PORT,
                 robot_radius: float = ROBOT_RADIUS, config: FoxgloveConfig | None = None,
                 image_provider: Callable[[str], Any] | None = None) -> None:
        import foxglove

        self.encoder = FoxgloveEncoder(bounds, robot_radius, config if config is not None else FoxgloveConfig.per_entity(),
                                       image_provider)
        self.context = foxglove.Context()
        self.channels = {
            s.topic: foxglove.Channel(s.topic, schema=foxglove.Schema(name=s.schema_name, encoding=s.schema_encoding,
                                                                       data=s.schema_data),
                                      message_encoding=s.message_encoding, context=self.context)
            for s in channel_specs(packed=self.encoder.config.packed)
        }
        import errno

        from swarmdeck.console.web.ws_relay import SubprotocolRelay

        self.server = foxglove.start_server(name="swarmdeck", host="127.0.0.1", port=0, context=self.context)
        try:
            self.relay = SubprotocolRelay(host, port, int(self.server.port))
        except OSError as exc:
            self.server.stop()
            for ch in self.channels.values():
                ch.close()
            if exc.errno == errno.EADDRINUSE:
                raise FoxglovePortInUse(f"Foxglove port {port} on {host} is in use") from None
            raise
        self.host = host
        self._pending: list[tuple[Frame, int]] = []
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self._service = ServiceThread(self._run, "swarmdeck-foxglove", wake=self._wake.set)
        self._t0: float | None = None
        self.sent = 0
        self.skipped = 0
        self.errors = 0
        self.last_error: str | None = None

    @property
    def port(self) -> int:
        """The TCP port clients connect to (the relay's)."""
        return self.relay.port

    @property
    def url(self) -> str:
        host = "127.0.0.1" if self.host in ("0.0.0.0", "") else self.host
        return f"ws://{host}:{self.port}"

    def offer(self, frame: Frame) -> None:
        """Called on the loop thread: queue the Frame with its wall-clock time and wake the bridge thread."""
        ns = time.time_ns()
        with self._lock:
            if len(self._pending) >= 256:  # far behind: keep the newest (events of dropped frames are lost)
                del self._pending[:128]
            self._pending.append((frame, ns))
        self._wake.set()

    def send_pending(self) -> int:
        """Send the newest pending Frame's channels and the skipped Frames' events; returns messages sent.
        (The thread's body; callable directly in tests.)"""
        with self._lock:
            batch, self._pending = self._pending, []
        if not batch:
            return 0
        n = 0
        try:
            for frame, ns in batch[:-1]:
                for text in frame.events:
                    self.channels[TOPIC_LOG].log(self.encoder.log(ns, text), log_time=ns)
                    n += 1
            self.skipped += len(batch) - 1
            frame, ns = batch[-1]
            if self._t0 is None:
                self._t0 = frame.time
            for topic, at, data in self.encoder.encode(frame, ns, frame.time - self._t0):
                self.channels[topic].log(data, log_time=at)
                n += 1
            self.sent += 1
        except Exception as exc:  # noqa: BLE001 - a viewer-side failure must never reach the loop
            self.errors += 1
            self.last_error = f"Foxglove bridge: {type(exc).__name__}: {exc}"
        return n

    def start(self) -> FoxgloveBridge:
        self._service.start()
        return self

    def _run(self) -> None:
        while not self._service.stopping:
            if not self._wake.wait(0.5):
                continue
            self._wake.clear()
            self.send_pending()

    def close(self) -> None:
        """Stop the thread and the server. Idempotent."""
        self._service.stop()
        self.relay.close()
        if self.server is not None:
            self.server.stop()
            self.server = None  # type: ignore[assignment]  # stopped: the attribute says so
        for ch in self.channels.values():
            ch.close()
