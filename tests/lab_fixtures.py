"""Helpers for the lab's tests (issue 30: several arenas, reservations, ETAs, notifications, remote runners): a
portal with several arenas on real uvicorn over loopback, a loopback SMTP server (aiosmtpd) and a loopback
webhook receiver that can answer 500 or hang. Registered in ``tests/conftest.py``'s ``pytest_plugins``."""
from __future__ import annotations

import json
import threading
import time
from dataclasses import dataclass, field
from email import message_from_bytes
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest
from portal_fixtures import Portal, skip_verification

from swarmdeck.console.portal.app import ServerThread, create_app
from swarmdeck.console.portal.arenas import ArenaSpec
from swarmdeck.console.portal.notify import SmtpSettings
from swarmdeck.console.portal.service import PortalConfig, PortalService
from swarmdeck.console.portal.submission import Limits

TWO_ARENAS = (ArenaSpec("floor", "simulated", robots=8), ArenaSpec("lab", "physical", robots=4))


def make_lab(tmp_path: Path, arenas: tuple[ArenaSpec, ...] = TWO_ARENAS, *, smtp: SmtpSettings | None = None,
             runner_lease_s: float = 20.0, max_upload_bytes: int = 64 << 10, max_duration: float = 600.0,
             grace_s: float = 15.0) -> Portal:
    """A portal with ``arenas`` (no runners started), users alice, bob (researchers), op1, op2 (operators)."""
    config = PortalConfig(data=tmp_path / "data", arenas=arenas, smtp=smtp, runner_lease_s=runner_lease_s,
                          limits=Limits(fleet=max(a.robots for a in arenas), max_duration=max_duration,
                                        max_upload_bytes=max_upload_bytes), verify_runs=1, grace_s=grace_s)
    service = PortalService(config)
    tokens = {name: service.accounts.add_user(name, role)[1]
              for name, role in (("alice", "researcher"), ("bob", "researcher"), ("carol", "researcher"),
                                 ("op1", "operator"), ("op2", "operator"))}
    return Portal(service, ServerThread(create_app(service)), tokens)


@pytest.fixture
def lab(tmp_path):
    p = make_lab(tmp_path)
    try:
        yield p
    finally:
        p.server.stop()
        p.service.close()


def queued(portal: Portal, who: str, **manifest) -> int:
    """Submit a job with ``manifest`` keys (name, robots, duration, arena, needs …) and move it to the arena
    queue as an accepting verification would; its id."""
    r = portal.submit(who, **manifest)
    assert r.status_code == 201, r.text
    job_id = r.json()["id"]
    skip_verification(portal, job_id)
    return job_id


@dataclass
class Hooks:
    """A loopback webhook receiver: ``url(path)``; what arrived at each path (``bodies[path]``); ``fail[path]``:
    answer 500 that many more times; ``hang``: paths that never answer (until the receiver stops)."""

    server: ThreadingHTTPServer
    bodies: dict[str, list[dict]] = field(default_factory=dict)
    fail: dict[str, int] = field(default_factory=dict)
    hang: set[str] = field(default_factory=set)
    tries: dict[str, int] = field(default_factory=dict)
    release: threading.Event = field(default_factory=threading.Event)

    def url(self, path: str) -> str:
        return f"http://127.0.0.1:{self.server.server_address[1]}{path}"


@pytest.fixture
def hooks():
    state: dict[str, Hooks] = {}

    class Handler(BaseHTTPRequestHandler):
        def do_POST(self):  # noqa: N802 - http.server's name
            h = state["h"]
            data = self.rfile.read(int(self.headers.get("Content-Length", 0)))
            h.tries[self.path] = h.tries.get(self.path, 0) + 1
            if self.path in h.hang:
                h.release.wait(30)
                return
            if h.fail.get(self.path, 0) > 0:
                h.fail[self.path] -= 1
                self.send_response(500)
                self.end_headers()
                return
            h.bodies.setdefault(self.path, []).append(json.loads(data))
            self.send_response(204)
            self.end_headers()

        def log_message(self, *args):
            pass

    server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    server.daemon_threads = True
    state["h"] = h = Hooks(server)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        yield h
    finally:
        h.release.set()
        server.shutdown()
        server.server_close()


@dataclass
class Mailbox:
    """The loopback SMTP server's messages (``messages``: email.message.Message), its host and port."""

    host: str
    port: int
    messages: list = field(default_factory=list)


@pytest.fixture
def smtp_server():
    from aiosmtpd.controller import Controller

    box: list = []

    class Handler:
        async def handle_DATA(self, server, session, envelope):  # noqa: N802 - aiosmtpd's name
            msg = message_from_bytes(envelope.content)
            msg["X-Rcpt"] = ",".join(envelope.rcpt_tos)
            box.append(msg)
            return "250 OK"

    import socket

    with socket.socket() as s:  # a free port (aiosmtpd checks its server by connecting to it: no port 0)
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    controller = Controller(Handler(), hostname="127.0.0.1", port=port)
    controller.start()
    try:
        yield Mailbox("127.0.0.1", port, box)
    finally:
        controller.stop()


def until(predicate, timeout: float = 60.0, what: str = "condition"):
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() > deadline:
            raise AssertionError(f"{what} not reached within {timeout} s")
        time.sleep(0.02)
