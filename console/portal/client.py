"""A small HTTP client of the portal's JSON API (what ``swarmdeck submit|jobs|results|cancel`` use).

``PortalClient(url, token)``: every method returns the decoded JSON or raises
:class:`ClientError` with the server's message and field (``status`` 0: the
server could not be reached).
"""
from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import httpx

from swarmdeck.console.portal.job import ExportState
from swarmdeck.console.portal.states import FINAL as FINAL_STATES
from swarmdeck.core.errors import SwarmdeckError


class ClientError(SwarmdeckError):
    def __init__(self, status: int, message: str, field: str | None = None) -> None:
        super().__init__(message)
        self.status, self.message, self.field = status, message, field

    def line(self) -> str:
        where = f" ({self.field})" if self.field else ""
        code = f"HTTP {self.status}: " if self.status else ""
        return f"{code}{self.message}{where}"


class PortalClient:
    def __init__(self, url: str, token: str, *, timeout: float = 60.0) -> None:
        if not url.startswith(("http://", "https://")):
            raise ValueError(f"the server URL must start with http:// or https://, got {url!r}")
        self.url = url.rstrip("/")
        self.http = httpx.Client(base_url=self.url, headers={"Authorization": f"Bearer {token}"}, timeout=timeout)

    def close(self) -> None:
        self.http.close()

    def __enter__(self) -> PortalClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _call(self, method: str, path: str, **kwargs: Any) -> httpx.Response:
        try:
            response = self.http.request(method, path, **kwargs)
        except httpx.HTTPError as exc:
            raise ClientError(0, f"cannot reach the server at {self.url}: {exc}") from None
        if response.status_code >= 400:
            try:
                body = response.json()
                message, field = str(body.get("error", response.text)), body.get("field")
            except (ValueError, AttributeError):
                message, field = response.text.strip()[:500] or response.reason_phrase, None
            raise ClientError(response.status_code, message, field)
        return response

    def submit(self, script: str | Path, manifest: dict[str, Any] | None, entry: str | None = None) -> dict[str, Any]:
        """Submit ``script`` (.py or .zip) with ``manifest`` (None: the archive's manifest.json); ``entry``: the
        script to run inside a .zip."""
        path = Path(script)
        data = {} if manifest is None else {"manifest": json.dumps(manifest)}
        if entry is not None:
            data["entry"] = entry
        with open(path, "rb") as f:
            return self._call("POST", "/api/jobs", files={"script": (path.name, f)}, data=data).json()

    def submit_sweep(self, script: str | Path, sweep: dict[str, Any], entry: str | None = None) -> dict[str, Any]:
        """Submit a parameter sweep of ``script`` as one job (``POST /api/sweeps``; ``sweep``: params, robots, seeds,
        seed, design, samples, duration, name)."""
        path = Path(script)
        data = {"sweep": json.dumps(sweep)}
        if entry is not None:
            data["entry"] = entry
        with open(path, "rb") as f:
            return self._call("POST", "/api/sweeps", files={"script": (path.name, f)}, data=data).json()

    def arena(self) -> dict[str, Any]:
        """The arena as operators see it (operator token): stopped, needs_operator, running, queue, fleet."""
        return self._call("GET", "/api/operator/arena").json()

    def env(self) -> dict[str, Any]:
        """What scripts can import on this portal (``GET /api/env``)."""
        return self._call("GET", "/api/env").json()

    def jobs(self) -> list[dict[str, Any]]:
        return self._call("GET", "/api/jobs").json()

    def job(self, job_id: int) -> dict[str, Any]:
        return self._call("GET", f"/api/jobs/{int(job_id)}").json()

    def cancel(self, job_id: int) -> dict[str, Any]:
        return self._call("POST", f"/api/jobs/{int(job_id)}/cancel").json()

    def results(self, job_id: int) -> dict[str, Any]:
        """An ended job's results summary (:func:`swarmdeck.console.portal.results.results_summary`)."""
        return self._call("GET", f"/api/jobs/{int(job_id)}/results").json()

    def files(self, job_id: int) -> list[dict[str, Any]]:
        return self._call("GET", f"/api/jobs/{int(job_id)}/files").json()

    def download(self, job_id: int, name: str, out: Path) -> int:
        """Write result file ``name`` to ``out`` (streamed); bytes written."""
        try:
            with self.http.stream("GET", f"/api/jobs/{int(job_id)}/files/{name}") as response:
                if response.status_code >= 400:
                    response.read()
                    body = response.json()
                    raise ClientError(response.status_code, body.get("error", ""), body.get("field"))
                written = 0
                tmp = out.with_name(out.name + ".part")
                with open(tmp, "wb") as f:
                    for chunk in response.iter_bytes():
                        f.write(chunk)
                        written += len(chunk)
                tmp.replace(out)
                return written
        except httpx.HTTPError as exc:
            raise ClientError(0, f"cannot reach the server at {self.url}: {exc}") from None

    def wait(self, job_id: int, *, poll_s: float = 1.0, on_state: Callable[[dict[str, Any]], None] | None = None,
             timeout: float | None = None) -> dict[str, Any]:
        """Poll until the job reaches a final state; the job."""
        deadline = None if timeout is None else time.monotonic() + timeout
        last = None
        while True:
            job = self.job(job_id)
            if job["state"] != last and on_state is not None:
                on_state(job)
            last = job["state"]
            if job["state"] in FINAL_STATES:
                return job
            if deadline is not None and time.monotonic() > deadline:
                raise ClientError(0, f"job {job_id} is still {job['state']} after {timeout:g} s")
            time.sleep(poll_s)

    def wait_exports(self, job_id: int, *, poll_s: float = 1.0, timeout: float | None = None) -> dict[str, Any]:
        """Poll until the job's exports are no longer being written (``exports`` not ``"writing"``); the job."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            job = self.job(job_id)
            if job.get("exports") != ExportState.WRITING:
                return job
            if deadline is not None and time.monotonic() > deadline:
                raise ClientError(0, f"job {job_id}'s exports are still being written after {timeout:g} s")
            time.sleep(poll_s)
