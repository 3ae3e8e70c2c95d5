"""The running console: control loop + viser server + scene + panel, with the scene drawn off the loop thread.

The loop hands each Frame to :class:`FrameViewer`, which only stores it
(latest-frame-wins) and wakes its own thread; that thread draws the newest
Frame and refreshes the panel. So any number of browser tabs, or a slow one,
never slows the loop: at worst frames are skipped in the drawing (viser then
also coalesces per node, so a slow tab sees the newest state, not a backlog).

From :data:`THIN_FROM` robots on the viewer also draws at most every :func:`draw_interval` s (0.25 s at
5000 robots, 0.5 s at 10,000): a scene update of thousands of robots costs the drawing thread tens of ms,
much of it holding the GIL the loop and the coverage workers also need, and the browser as long to apply
(at 10,000 robots a page updated every Frame was too busy to take the emergency-stop click in time).
"""
from __future__ import annotations

import threading
import time
from collections.abc import Callable

from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.loop import ControlLoop
from swarmdeck.console.web.gui import ConsoleGui
from swarmdeck.console.web.scene import ArenaScene
from swarmdeck.core.ports import ProvidesImage
from swarmdeck.core.service_thread import ServiceThread

#: robots from which the console's viewer thins its scene draws (:func:`draw_interval`)
THIN_FROM = 2000
#: robots drawn per second of spacing between draws when thinned: interval = N / this (s)
THIN_ROBOTS_PER_S = 20000.0


def draw_interval(n_robots: int) -> float:
    """Least time between two scene draws, s, for ``n_robots`` robots: 0 (every Frame the viewer gets)
    below :data:`THIN_FROM`, else N / :data:`THIN_ROBOTS_PER_S` (0.25 s at 5000, 0.5 s at 10,000)."""
    n = int(n_robots)
    return 0.0 if n < THIN_FROM else n / THIN_ROBOTS_PER_S


class FrameViewer:
    """Draws the newest Frame on its own thread (latest-frame-wins), at most every ``min_interval`` s
    (0: as often as Frames come; ``clock``: monotonic seconds, for tests). ``interval_for``: a viewer that does not
    know its robot count in advance (the portal's operator view: each job has its own) also waits at least
    ``interval_for(N)`` s after drawing a Frame of N robots (:func:`draw_interval`)."""

    def __init__(self, scene: ArenaScene, gui: ConsoleGui | None = None,
                 on_error: Callable[[str], None] | None = None, min_interval: float = 0.0,
                 clock: Callable[[], float] = time.monotonic,
                 interval_for: Callable[[int], float] | None = None) -> None:
        if not min_interval >= 0.0:
            raise ValueError(f"min_interval must be >= 0 s, got {min_interval!r}")
        self.scene, self.gui = scene, gui
        self.min_interval = float(min_interval)
        self.interval_for = interval_for
        self._clock = clock
        self._last_draw: float | None = None
        self._last_n = 0
        self._pending: Frame | None = None
        self._lock = threading.Lock()
        self._wake = threading.Event()
        self._service = ServiceThread(self._run, "swarmdeck-viewer", wake=self._wake.set)
        self.drawn = 0
        self.skipped = 0
        self.errors = 0
        self.last_error: str | None = None
        self._on_error = on_error

    def offer(self, frame: Frame) -> None:
        """Called on the loop thread: keep only the newest frame and wake the drawing thread."""
        with self._lock:
            if self._pending is not None:
                self.skipped += 1
            self._pending = frame
        if self.gui is not None:
            self.gui.record(frame)
        self._wake.set()

    def start(self) -> FrameViewer:
        self._service.start()
        return self

    def until_next(self) -> float:
        """Seconds the thread still waits before it may draw again (0: now)."""
        interval = self.min_interval
        if self.interval_for is not None:
            interval = max(interval, self.interval_for(self._last_n))
        if self._last_draw is None or interval <= 0.0:
            return 0.0
        return max(0.0, self._last_draw + interval - self._clock())

    def draw_pending(self) -> Frame | None:
        """Draw the newest pending frame now (the thread's body; callable directly in tests)."""
        with self._lock:
            frame, self._pending = self._pending, None
        if frame is None:
            return None
        self._last_draw = self._clock()
        self._last_n = frame.n
        try:
            self.scene.draw(frame)
            if self.gui is not None:
                self.gui.update(frame)
            self.drawn += 1
        except Exception as exc:  # a broken tab or a drawing bug must not stop the console
            self.errors += 1
            msg = f"drawing failed: {type(exc).__name__}: {exc}"
            if msg != self.last_error and self._on_error is not None:
                self._on_error(msg)
            self.last_error = msg
        return frame

    def _run(self) -> None:
        while not self._service.stopping:
            if not self._wake.wait(0.5):
                continue
            self._wake.clear()
            wait = self.until_next()
            if wait > 0.0 and self._service.wait(wait):  # thinned: the newest Frame at the end of the wait
                return
            self.draw_pending()

    def stop(self) -> None:
        self._service.stop()


class ConsoleApp:
    """A loop shown in a browser: ``ConsoleApp(loop, host, port).start()``; ``url``; ``close()``.

    Args:
        loop: the control loop (not yet started).
        host: interface to bind (127.0.0.1 by default: not reachable from other machines).
        port: TCP port; 0 picks a free one.
    """

    def __init__(self, loop: ControlLoop, host: str = "127.0.0.1", port: int = 8080, verbose: bool = False) -> None:
        import viser

        self.loop = loop
        self.server: viser.ViserServer = viser.ViserServer(host=host, port=port, verbose=verbose)
        self.scene = ArenaScene(self.server, loop.config.bounds, robot_radius=loop.robot.radius,
                                image_provider=loop.source.image if isinstance(loop.source, ProvidesImage) else None)
        self.gui = ConsoleGui(self.server, loop, self.scene)
        self.viewer = FrameViewer(self.scene, self.gui, on_error=loop.post,
                                  min_interval=draw_interval(loop.config.n_robots))
        self._unsubscribe = loop.subscribe(self.viewer.offer)
        self.host = host

    @property
    def port(self) -> int:
        return int(self.server.get_port())

    @property
    def url(self) -> str:
        host = "127.0.0.1" if self.host in ("0.0.0.0", "") else self.host
        return f"http://{host}:{self.port}"

    def start(self) -> ConsoleApp:
        """Draw the first frame, then start the viewer and the loop threads."""
        frame = self.loop.tick() if self.loop.latest is None else self.loop.latest
        self.scene.draw(frame)
        self.gui.update(frame, force=True)
        self.viewer.start()
        self.loop.start()
        return self

    def wait(self, duration: float | None = None) -> None:
        """Block for ``duration`` s of wall time (forever when None) while the threads run."""
        start = time.monotonic()
        while duration is None or time.monotonic() - start < duration:
            time.sleep(0.1)

    def close(self) -> None:
        """Stop the loop (robots stop), the viewer and the server."""
        self._unsubscribe()
        try:
            self.loop.close()
        finally:
            self.viewer.stop()
            self.server.stop()
