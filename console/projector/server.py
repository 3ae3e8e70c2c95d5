"""The projector page's server: the newest Frame, its projector picture over Server-Sent Events, the page.

``swarmdeck console --projector [PORT]`` runs one :class:`ProjectorServer` beside the console: the loop hands it
every Frame (:meth:`ProjectorServer.offer`, O(1) on the loop thread: it keeps only the newest), and each page
(``http://HOST:PORT/projector``; any number of them) gets its own stream that always sends the newest Frame and
skips the ones it had no time for — a slow page drops frames, it never lags. Serialisation happens once per
Frame and settings version, on the first stream thread that needs it, never on the loop thread.

Routes: ``/projector`` (the page), ``/projector/projector.js``, ``/projector/next`` (what the page uses: a long
poll answering the newest config and Frame; the page asks again on each answer, so at most one message is on its
way — Server-Sent Events have no back-pressure, and a page slower than the loop would fall behind on a buffered
stream), ``/projector/stream`` (the same as SSE: a ``config`` event on connect and after every settings change,
then ``frame`` events, for tools), ``/projector/state`` (JSON: seq, settings, calibrated, pages served, frames
sent and skipped).
"""
from __future__ import annotations

import json
import secrets
import threading
import time
from dataclasses import replace
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from typing import Any

import msgspec

from swarmdeck.console.projector.message import config_message, projector_message
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.params import ProjectorParams
from swarmdeck.core.bounds import Bounds
from swarmdeck.core.service_thread import ServiceThread
from swarmdeck.tracking.projector import ProjectorCalibration, ProjectorCalibrationError, check_projector_homography

#: A stream with nothing new sends a comment this often, s (finds pages that went away).
KEEPALIVE_S = 1.0


class ProjectorFeed:
    """The newest Frame and the projector settings, thread-safe; serialised messages cached per
    (sequence number, settings version)."""

    def __init__(self, bounds: Bounds, calibration: ProjectorCalibration | None,
                 settings: ProjectorParams | None = None) -> None:
        self.bounds = Bounds.of(bounds)
        self.calibration = calibration
        self._settings = settings if settings is not None else ProjectorParams()
        self._version = 0
        self._frame: Frame | None = None
        self._stamp = 0.0
        self._seq = 0
        self._cache: tuple[tuple[int, int], str] | None = None
        self._cond = threading.Condition()
        self.closed = False
        self.instance = secrets.token_hex(6)  # a page polling a restarted server starts again from scratch
        self.errors = 0
        self.last_error: str | None = None

    @property
    def settings(self) -> ProjectorParams:
        """The settings in force."""
        with self._cond:
            return self._settings

    def offer(self, frame: Frame) -> None:
        """Keep ``frame`` as the newest (the loop's subscriber; O(1))."""
        with self._cond:
            self._frame, self._stamp = frame, time.time() * 1000.0
            self._seq += 1
            self._cond.notify_all()

    def set(self, **changes: Any) -> ProjectorParams:
        """Change settings (``ProjectorParams`` fields; ValueError naming a bad one); pages redraw at once."""
        with self._cond:
            new = replace(self._settings, **changes)
            self._settings = new
            self._version += 1
            self._cond.notify_all()
            return new

    def close(self) -> None:
        """Wake every stream so it ends."""
        with self._cond:
            self.closed = True
            self._cond.notify_all()

    def version(self) -> int:
        """The settings version."""
        with self._cond:
            return self._version

    def config_json(self) -> tuple[int, str]:
        """(version, the ``config`` event's JSON)."""
        with self._cond:
            v, s = self._version, self._settings
        return v, json.dumps({**config_message(self.bounds, self.calibration, s, v), "instance": self.instance})

    def wait_newer(self, seq: int, version: int, timeout: float) -> tuple[int, int] | None:
        """Block until a Frame newer than ``seq`` or settings newer than ``version`` (or ``timeout`` s, or
        close): the current (seq, version), or None when nothing changed."""
        with self._cond:
            self._cond.wait_for(lambda: self.closed or self._seq > seq or self._version > version, timeout)
            if self.closed or (self._seq <= seq and self._version <= version):
                return None
            return self._seq, self._version

    def message(self) -> tuple[int, int, str] | None:
        """(seq, version, JSON) of the newest Frame drawn with the current settings; None before the first."""
        with self._cond:
            frame, seq, v, s, stamp = self._frame, self._seq, self._version, self._settings, self._stamp
            cached = self._cache
        if frame is None:
            return None
        if cached is not None and cached[0] == (seq, v):
            return seq, v, cached[1]
        try:
            text = msgspec.json.encode(projector_message(frame, seq, s, stamp)).decode()  # ≈ 6× json's speed
        except (ValueError, TypeError, msgspec.EncodeError) as exc:  # a Frame that cannot be drawn must not end the stream
            self.errors += 1
            self.last_error = f"{type(exc).__name__}: {exc}"
            return None
        with self._cond:
            self._cache = ((seq, v), text)
        return seq, v, text


def _static(name: str) -> bytes:
    return resources.files("swarmdeck.console.projector.static").joinpath(name).read_bytes()


class _Handler(BaseHTTPRequestHandler):
    server: _Server
    protocol_version = "HTTP/1.1"
    disable_nagle_algorithm = True  # headers and body are two writes: Nagle + delayed ACK would add 40 ms each

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - the stdlib's signature
        """Quiet: the console prints its own lines."""

    def _send(self, body: bytes, ctype: str, status: HTTPStatus = HTTPStatus.OK) -> None:
        self.send_response(status)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        self.wfile.write(body)

    def do_GET(self) -> None:  # noqa: N802 - the stdlib's name
        path = self.path.split("?", 1)[0].rstrip("/") or "/"
        if self.server.owner.feed.closed:  # kept-alive connections outlive the listening socket: end them
            self.close_connection = True
            self._send(b"the projector server has stopped\n", "text/plain; charset=utf-8",
                       HTTPStatus.SERVICE_UNAVAILABLE)
            return
        if path in ("/", "/projector"):
            self._send(_static("projector.html"), "text/html; charset=utf-8")
        elif path == "/projector/projector.js":
            self._send(_static("projector.js"), "text/javascript; charset=utf-8")
        elif path == "/projector/state":
            self._send(json.dumps(self.server.owner.state()).encode(), "application/json")
        elif path == "/projector/stream":
            self._stream()
        elif path == "/projector/next":
            self._next()
        else:
            self._send(b"not found: the projector page is /projector\n", "text/plain; charset=utf-8",
                       HTTPStatus.NOT_FOUND)

    def _next(self) -> None:
        """Long poll: ``?seq=S&version=V&instance=I`` → the config (when newer than V) and the newest Frame (when newer than
        S or with new settings) as one JSON ``{"config": …|null, "frame": …|null}``, waiting up to
        :data:`KEEPALIVE_S` for one. The page asks again when it has the answer, so at most one message is ever
        on its way: a slow page skips Frames, it never lags behind. ``instance`` is the config's: a page that knew
        another server (this one restarted) is answered as a new page."""
        owner = self.server.owner
        feed = owner.feed
        query = dict(p.split("=", 1) for p in (self.path.split("?", 1) + [""])[1].split("&") if "=" in p)
        try:
            seq, version = int(query.get("seq", "0")), int(query.get("version", "-1"))
        except ValueError:
            self._send(b"seq and version must be whole numbers\n", "text/plain; charset=utf-8",
                       HTTPStatus.BAD_REQUEST)
            return
        if query.get("instance", feed.instance) != feed.instance:  # the page knew a server that has since restarted
            seq, version = 0, -1
        if seq == 0 and version == -1:
            owner.count("pages")
        if feed.version() == version:
            got = feed.message()
            if got is None or got[0] <= seq:
                feed.wait_newer(seq, version, KEEPALIVE_S)
        config = None
        if feed.version() != version:
            config = feed.config_json()[1]
        got = feed.message()
        frame = None
        if got is not None and (got[0] > seq or config is not None):
            if seq > 0 and got[0] > seq + 1:
                owner.count("skipped", got[0] - seq - 1)
            frame = got[2]
            owner.count("sent")
        if feed.closed:
            self.close_connection = True
            self._send(b"the projector server has stopped\n", "text/plain; charset=utf-8",
                       HTTPStatus.SERVICE_UNAVAILABLE)
            return
        body = f'{{"config": {config or "null"}, "frame": {frame or "null"}}}'.encode()
        self._send(body, "application/json")

    def _stream(self) -> None:
        owner = self.server.owner
        feed = owner.feed
        self.send_response(HTTPStatus.OK)
        self.send_header("Content-Type", "text/event-stream")
        self.send_header("Cache-Control", "no-store")
        self.send_header("Connection", "close")
        self.end_headers()
        self.close_connection = True
        owner.count("pages")
        seq, version = 0, -1
        try:
            while not feed.closed:
                fresh = False
                if feed.version() != version:  # settings changed: new config, then the newest Frame redrawn
                    version, text = feed.config_json()
                    self.wfile.write(f"event: config\ndata: {text}\n\n".encode())
                    self.wfile.flush()
                    fresh = True
                got = feed.message()
                if got is not None and (got[0] > seq or fresh):
                    if seq > 0 and got[0] > seq + 1:
                        owner.count("skipped", got[0] - seq - 1)
                    seq = got[0]
                    self.wfile.write(f"event: frame\ndata: {got[2]}\n\n".encode())
                    self.wfile.flush()
                    owner.count("sent")
                if feed.wait_newer(seq, version, KEEPALIVE_S) is None and not feed.closed:
                    self.wfile.write(b": keep-alive\n\n")
                    self.wfile.flush()
        except (BrokenPipeError, ConnectionResetError, TimeoutError, OSError):
            return  # the page went away


class _Server(ThreadingHTTPServer):
    daemon_threads = True
    allow_reuse_address = True
    owner: ProjectorServer

    def handle_error(self, request: Any, client_address: Any) -> None:
        """A page that went away mid-answer is normal (no traceback); anything else is counted."""
        import sys

        exc = sys.exc_info()[1]
        if isinstance(exc, (ConnectionError, TimeoutError)):
            return
        self.owner.feed.errors += 1
        self.owner.feed.last_error = f"{type(exc).__name__}: {exc}"


class ProjectorServer:
    """The projector page on ``http://host:port/projector`` (port 0: a free one), fed by :meth:`offer`.

    Args:
        bounds: the arena, m.
        calibration: the floor → projector homography (``swarmdeck calibrate projector``), or None: the page
            says so on the floor.
        host, port: where to serve (127.0.0.1: this machine only; the projector's browser usually runs here).
        settings: the initial layers / brightness / blackout.
    """

    def __init__(self, bounds: Bounds, calibration: ProjectorCalibration | None = None, host: str = "127.0.0.1",
                 port: int = 8090, settings: ProjectorParams | None = None) -> None:
        self.feed = ProjectorFeed(bounds, calibration, settings)
        self.host = host
        self._httpd = _Server((host, port), _Handler)
        self._httpd.owner = self
        self._counts = {"pages": 0, "sent": 0, "skipped": 0}
        self._lock = threading.Lock()
        self._service = ServiceThread(self._httpd.serve_forever, "swarmdeck-projector", join_timeout=5.0,
                                      wake=self._httpd.shutdown)

    @property
    def port(self) -> int:
        """The TCP port served."""
        return int(self._httpd.server_address[1])

    @property
    def url(self) -> str:
        """The page's address."""
        host = "127.0.0.1" if self.host in ("0.0.0.0", "") else self.host
        return f"http://{host}:{self.port}/projector"

    @property
    def settings(self) -> ProjectorParams:
        """The settings in force."""
        return self.feed.settings

    def set(self, **changes: Any) -> ProjectorParams:
        """Change the layers / brightness / blackout (:class:`ProjectorParams` fields)."""
        return self.feed.set(**changes)

    def offer(self, frame: Frame) -> None:
        """The loop's subscriber: keep the newest Frame."""
        self.feed.offer(frame)

    def count(self, key: str, k: int = 1) -> None:
        """Count pages served, frames sent and frames skipped."""
        with self._lock:
            self._counts[key] += k

    def state(self) -> dict[str, Any]:
        """What the server did so far (``/projector/state``)."""
        with self._lock:
            counts = dict(self._counts)
        got = self.feed.message()
        return {"seq": None if got is None else got[0], "calibrated": self.feed.calibration is not None,
                "settings": json.loads(self.feed.config_json()[1])["settings"],
                "errors": self.feed.errors, "last_error": self.feed.last_error, **counts}

    def start(self) -> ProjectorServer:
        """Serve on a background thread."""
        self._service.start()
        return self

    def close(self) -> None:
        """End every stream and stop serving."""
        self.feed.close()
        if self._service.started:
            self._service.stop()  # wakes serve_forever through shutdown()
        self._httpd.server_close()


def projector_calibration(path: str | None, bounds: Bounds) -> ProjectorCalibration | None:
    """The calibration a ``--projector`` command uses: ``path``, else ``./projector.json`` when it exists, else
    None (the page then asks for one). :class:`ProjectorCalibrationError` naming the problem when the file is
    unusable or its homography does not put the arena ``bounds`` on the projector's image."""
    from pathlib import Path

    if path is None:
        if not Path("projector.json").is_file():
            return None
        path = "projector.json"
    cal = ProjectorCalibration.load(path)
    why = check_projector_homography(cal.homography, bounds, cal.size)
    if why is not None:
        raise ProjectorCalibrationError(f"{path} on the arena {tuple(Bounds.of(bounds))}: {why}")
    return cal
