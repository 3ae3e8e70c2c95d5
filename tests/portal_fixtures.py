"""Helpers for the portal's tests: a portal served by real uvicorn on loopback, in this process or as
``swarmdeck server`` in its own process, on a real SQLite file in the test's folder.

The fixture ``portal`` (in-process) is registered for every test by ``pytest_plugins`` in ``tests/conftest.py``;
import the helpers (``sign_in``, ``wait_for_state``, …) by name, or use :func:`start_server` (a child process,
for kill -9 and the CLI).
"""
from __future__ import annotations

import os
import queue
import re
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import httpx
import pytest

from swarmdeck.console.portal.app import HttpSettings, ServerThread, create_app
from swarmdeck.console.portal.quotas import Quotas
from swarmdeck.console.portal.service import PortalConfig, PortalService
from swarmdeck.console.portal.submission import Limits

SPIN = ("import numpy as np\n"
        "def experiment(arena):\n"
        "    while True:\n"
        "        arena.set_unicycle(np.full(arena.n, 0.02), np.full(arena.n, 0.5))\n"
        "        arena.step()\n")
CRASH = "def experiment(arena):\n    arena.step()\n    raise KeyError('oops')\n"
CLI = [sys.executable, "-c", "import sys; from swarmdeck.console.cli import main; sys.exit(main())"]


def manifest(name: str = "spin", robots: int = 2, duration: float = 1.0, **extra) -> dict:
    return {"name": name, "robots": robots, "duration": duration, **extra}


@dataclass
class Portal:
    """An in-process portal: ``service``, ``url``, tokens ``alice``/``bob`` (researchers), ``op1``/``op2``."""

    service: PortalService
    server: ServerThread
    tokens: dict[str, str] = field(default_factory=dict)

    @property
    def url(self) -> str:
        return self.server.url

    def client(self, who: str | None) -> httpx.Client:
        headers = {} if who is None else {"Authorization": f"Bearer {self.tokens[who]}"}
        return httpx.Client(base_url=self.url, headers=headers, timeout=30)

    def submit(self, who: str, source: str | bytes = SPIN, filename: str = "spin.py", data: dict | None = None,
               **kwargs) -> httpx.Response:
        import json

        body = {"manifest": json.dumps(manifest(**kwargs))} if data is None else data
        with self.client(who) as c:
            return c.post("/api/jobs", files={"script": (filename, source)}, data=body)


CSRF = re.compile(r'name="csrf" value="([^"]*)"')


def sign_in(portal: Portal, who: str) -> tuple[httpx.Client, str]:
    """A browser-like client signed in through the sign-in form; (client, the session's CSRF token)."""
    c = httpx.Client(base_url=portal.url, timeout=30)
    nonce = CSRF.search(c.get("/signin").text).group(1)
    r = c.post("/signin", data={"csrf": nonce, "token": portal.tokens[who]})
    assert r.status_code == 303, r.text
    return c, c.get("/api/me").json()["csrf"]


def make_portal(tmp_path: Path, *, http: HttpSettings | None = None, quotas: Quotas | None = None,
                retain_days: float | None = None, verify_runs: int = 1, arenas: tuple = (), **limits) -> Portal:
    config = PortalConfig(data=tmp_path / "data", limits=Limits(**limits), verify_runs=verify_runs,
                          quotas=quotas if quotas is not None else Quotas(), retain_days=retain_days, arenas=arenas)
    service = PortalService(config)
    tokens = {}
    for name, role in (("alice", "researcher"), ("bob", "researcher"), ("op1", "operator"), ("op2", "operator")):
        tokens[name] = service.accounts.add_user(name, role)[1]
    server = ServerThread(create_app(service, http=http), http=http)
    return Portal(service, server, tokens)


@pytest.fixture
def portal(tmp_path):
    p = make_portal(tmp_path, fleet=6, max_duration=60.0, max_upload_bytes=64 << 10)
    try:
        yield p
    finally:
        p.server.stop()
        p.service.close()


class ServerProcess:
    """``swarmdeck server`` in its own process; ``url`` once it printed its address."""

    def __init__(self, data: Path, *extra: str, timeout: float = 60.0) -> None:
        # its own process group, so that stop() can end the verification pool's workers a kill -9 orphaned
        self.proc = subprocess.Popen([*CLI, "server", "--data", str(data), "--port", "0", *extra],
                                     stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                     start_new_session=True)
        self.lines: queue.Queue[str] = queue.Queue()
        self.output: list[str] = []
        threading.Thread(target=self._read, daemon=True).start()
        deadline = time.monotonic() + timeout
        self.url = ""
        while not self.url:
            try:
                line = self.lines.get(timeout=max(0.01, deadline - time.monotonic()))
            except queue.Empty:
                self.proc.kill()
                raise AssertionError(f"the server did not start within {timeout} s: {''.join(self.output)}") from None
            if line.startswith("swarmdeck server: http://"):
                self.url = line.split()[2]

    def _read(self) -> None:
        for line in self.proc.stdout:
            self.output.append(line)
            self.lines.put(line)

    def stop(self) -> int:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        try:  # what the server started and did not end (its pool's workers after a kill -9), as a service manager would
            os.killpg(self.proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        return self.proc.returncode


def start_server(data: Path, *extra: str) -> ServerProcess:
    return ServerProcess(data, *extra)


def add_user(data: Path, name: str, role: str) -> str:
    """``swarmdeck users add`` as a user would run it; the token it prints."""
    out = subprocess.run([*CLI, "users", "add", name, "--role", role, "--data", str(data)], capture_output=True,
                         text=True, timeout=60, check=True).stdout
    return out.strip().splitlines()[-1]


def wait_for_state(client: httpx.Client, job_id: int, states: tuple[str, ...], timeout: float = 90.0) -> dict:
    """Poll the job until its state is one of ``states``; fail naming the state it is stuck in."""
    deadline = time.monotonic() + timeout
    while True:
        job = client.get(f"/api/jobs/{job_id}").json()
        if job["state"] in states:
            return job
        if time.monotonic() > deadline:
            raise AssertionError(f"job {job_id} is {job['state']}, not {states}, after {timeout} s: {job}")
        time.sleep(0.05)


def skip_verification(portal: Portal, job_id: int, verdict: str = "accepted") -> None:
    """Move a submitted job straight into the arena queue as if verification had accepted it (tests of the arena
    and its pages that do not need a verifier), and wake the runner."""
    svc = portal.service
    with svc.db.transaction() as tx:
        for state in ("verifying", "awaiting approval", "in arena queue"):
            svc.db.transition(tx, job_id, state, **({"verdict": verdict} if state == "awaiting approval" else {}))
    svc.notify()


def browser_sign_in(page, portal: Portal, who: str) -> None:
    """Sign ``who`` in on a Playwright page with their token; it lands on Operator (operators) or My jobs."""
    page.goto(f"{portal.url}/signin")
    page.fill("#token", portal.tokens[who])
    page.click("button[type=submit]")
    page.wait_for_url("**/operator" if who.startswith("op") else "**/jobs")
