"""Remote arena runners, the runner's side: ``swarmdeck runner --portal URL --arena NAME --token T``.

The same :class:`~.runner.ArenaRunner` as inside the portal (the fleet, set-up and return, the control loop, the
sandbox, the recording) runs on this machine; :class:`PortalLink` stands in for the portal's service and speaks
to the portal over HTTP (the routes: :mod:`.remote_api`; the rules: :mod:`.remote`):

* it connects for the arena (one lease; 409 while another runner holds the arena), then asks which job the
  plan puts on this arena, checks its robots for it and claims exactly that job;
* it downloads the job's files into ``WORK/jobs/<id>/``; while the job runs, a heartbeat thread says it is alive
  every ``heartbeat_s`` (a cancel or an emergency stop comes back in the answer and ends the run within a tick)
  and sends the recording as it grows, by offset — so if this process dies, the portal keeps the recording up
  to the last heartbeat and recovers it when the lease runs out;
* at the end it sends the rest of the recording, ``script.log`` and ``run.json``, then the job's end; the
  exports are written by the portal.

A lost lease (the portal did not hear from this runner for ``lease_s``: a network cut) ends the running job
here, and the runner connects again.
"""
from __future__ import annotations

import io
import threading
import zipfile
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any, cast

import httpx

from swarmdeck.console.portal.client import ClientError
from swarmdeck.console.portal.exports import JobExports
from swarmdeck.console.portal.job import Job
from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.portal.service import PortalConfig, PortalService
from swarmdeck.console.portal.states import JobState
from swarmdeck.core.service_thread import ServiceThread


class LeaseLost(ClientError):
    """The portal no longer counts this runner as its arena's (409 on the lease)."""


class NoExports(JobExports):
    """The portal writes a remote job's exports: nothing is exported on the runner's machine."""

    def submit(self, job_id: int) -> None:
        return None

    def resume(self) -> list[int]:
        return []


class PortalLink:
    """What :class:`~.runner.ArenaRunner` asks of the portal, over HTTP (module docstring)."""

    def __init__(self, url: str, token: str, arena: str, work: Path, config: PortalConfig, *,
                 timeout_s: float = 30.0) -> None:
        self.url, self.arena, self.work = url.rstrip("/"), arena, Path(work)
        self.http = httpx.Client(base_url=self.url, headers={"Authorization": f"Bearer {token}"}, timeout=timeout_s)
        self.config = config
        self.lease = ""
        self.spec: dict[str, Any] = {}
        self.heartbeat_s = 1.0
        self.max_piece = 1 << 20
        self._stopped = False
        self._wake = threading.Event()
        self._sent: dict[int, int] = {}  # job id -> bytes of its recording the portal has
        self._lock = threading.Lock()

    # ------------------------------------------------------------------ HTTP
    def _call(self, method: str, path: str, **kwargs: Any) -> Any:
        try:
            r = self.http.request(method, path, **kwargs)
        except httpx.HTTPError as exc:
            raise ClientError(0, f"cannot reach the portal at {self.url}: {exc}") from None
        if r.status_code >= 400:
            try:
                body = r.json()
                message, field = str(body.get("error", r.text)), body.get("field")
            except ValueError:
                message, field = r.text[:200], None
            kind = LeaseLost if r.status_code == 409 and field == "lease" else ClientError
            raise kind(r.status_code, message, field)
        return r.json() if r.headers.get("content-type", "").startswith("application/json") else r.content

    def _lease(self, **extra: Any) -> dict[str, Any]:
        return {"arena": self.arena, "lease": self.lease, **extra}

    def connect(self) -> dict[str, Any]:
        """Take the arena (ClientError 409 while another runner holds it)."""
        answer = self._call("POST", "/api/runner/connect", json={"arena": self.arena})
        self.lease, self.spec = answer["lease"], answer["arena"]
        self.heartbeat_s, self.max_piece = float(answer["heartbeat_s"]), int(answer["max_piece"])
        self.config = replace(self.config, grace_s=float(answer["grace_s"]),
                              arena_tick_budget_s=answer["tick_budget_s"])
        return cast(dict[str, Any], answer)

    # ------------------------------------------------------------------ what ArenaRunner asks of its service
    def notify(self) -> None:
        self._wake.set()

    def wait_for_change(self, timeout: float) -> None:
        self._wake.wait(min(timeout, self.heartbeat_s))
        self._wake.clear()

    @property
    def arena_stopped(self) -> bool:
        return self._stopped

    def claim_for_arena(self, admit: Any = None, arena: str | None = None) -> Job | None:
        """Which job the plan puts on this arena now; ``admit(job)`` checks the robots; then claim exactly it."""
        try:
            answer = self._call("POST", "/api/runner/claim", json=self._lease())
            self._stopped = bool(answer["stopped"])
            if answer["job"] is None:
                return None
            job = _job(answer["job"])
            why = None if admit is None else admit(job)
            if why is not None:
                self._call("POST", "/api/runner/claim", json=self._lease(job=job.id, wait=why))
                return None
            answer = self._call("POST", "/api/runner/claim", json=self._lease(job=job.id))
            if not answer.get("claimed") or answer["job"] is None:
                return None
            job = _job(answer["job"])
        except ClientError:
            return None  # the portal is away or the lease ended (the heartbeat connects again): ask later
        try:
            self._fetch(job)
        except (ClientError, OSError, zipfile.BadZipFile) as exc:
            self.finish_run(job.id, JobState.FAILED, f"the arena runner could not fetch the job's files: {exc}")
            return None
        return job

    def _fetch(self, job: Job) -> None:
        data = self._call("GET", f"/api/runner/jobs/{job.id}/bundle", params=self._lease())
        folder = self.job_dir(job.id)
        with zipfile.ZipFile(io.BytesIO(data)) as z:
            for info in z.infolist():
                target = (folder / info.filename).resolve()
                if folder.resolve() not in target.parents or info.is_dir():
                    continue
                target.parent.mkdir(parents=True, exist_ok=True)
                target.write_bytes(z.read(info))

    def job_dir(self, job_id: int) -> Path:
        folder = self.work / "jobs" / str(int(job_id))
        folder.mkdir(parents=True, exist_ok=True)
        return folder

    def script(self, job: Job) -> tuple[Path, str | None]:
        folder = self.job_dir(job.id)
        return (folder / "script.py", None) if job.kind == "py" else (folder / "src", job.entry)

    def mark_running(self, job_id: int) -> bool:
        try:
            return bool(self._call("POST", f"/api/runner/jobs/{job_id}/running", json=self._lease())["ok"])
        except ClientError:
            return False  # the job is no longer this runner's: it ends

    def job_state(self, job_id: int) -> JobState | None:
        try:
            answer = self._call("POST", "/api/runner/heartbeat", json=self._lease(job=int(job_id)))
        except LeaseLost:
            return None
        except ClientError:
            return JobState.SETTING_UP  # the portal is away for a moment: the heartbeat and the lease decide
        return None if answer["state"] is None else JobState(answer["state"])

    def heartbeat(self, job_id: int | None) -> dict[str, Any]:
        answer = self._call("POST", "/api/runner/heartbeat", json=self._lease(job=job_id))
        self._stopped = bool(answer["stopped"])
        return cast(dict[str, Any], answer)

    def send_recording(self, job_id: int) -> None:
        """Send what the recording grew by since the last call."""
        with self._lock:
            path = self.job_dir(job_id) / "recording.mcap"
            if not path.is_file():
                return
            sent = self._sent.get(job_id, 0)
            with open(path, "rb") as f:
                f.seek(sent)
                while piece := f.read(self.max_piece):
                    sent = self._put(job_id, "recording.mcap", sent, piece)
            self._sent[job_id] = sent

    def _put(self, job_id: int, name: str, offset: int, data: bytes) -> int:
        answer = self._call("PUT", f"/api/runner/jobs/{job_id}/files/{name}",
                            params=self._lease(offset=offset), content=data)
        return int(answer["size"])

    def finish_run(self, job_id: int, state: JobState, reason: str | None) -> JobState | None:
        """Send the rest of the recording, ``script.log`` and ``run.json``, then the job's end."""
        try:
            self.send_recording(job_id)
            folder = self.job_dir(job_id)
            for name in ("script.log", "run.json"):
                if (folder / name).is_file():
                    data = (folder / name).read_bytes()
                    offset = 0
                    for k in range(0, max(len(data), 1), self.max_piece):
                        offset = self._put(job_id, name, offset, data[k:k + self.max_piece])
            answer = self._call("POST", f"/api/runner/jobs/{job_id}/finish",
                                json=self._lease(state=str(state), reason=reason))
        except ClientError:
            return None  # the lease ended (the portal interrupted the job) or the portal is away
        return None if answer["state"] is None else JobState(answer["state"])

    def arena_needs_operator(self, message: str) -> None:
        try:
            self._call("POST", "/api/runner/attention", json=self._lease(message=message))
        except ClientError:
            pass
        self._stopped = True

    def recover_on_start(self) -> list[int]:
        return []

    def close(self) -> None:
        self.http.close()


def _job(data: dict[str, Any]) -> Job:
    """A job from its API JSON (the attributes the runner reads)."""
    poses = data.get("initial_poses")
    return Job(id=int(data["id"]), user_id=0, owner=str(data["owner"]), name=str(data["name"]),
               state=JobState(data["state"]), held_from=None, kind=str(data["kind"]), script=str(data["script"]),
               entry=str(data["entry"]), robots=int(data["robots"]), duration=float(data["duration"]),
               initial_poses=None if poses is None else tuple(tuple(float(v) for v in p) for p in poses),
               request_no_barrier=bool(data["request_no_barrier"]), barrier_forbidden=bool(data["barrier_forbidden"]),
               verdict=data.get("verdict"), safety_score=data.get("safety_score"), bypass=data.get("bypass"),
               reason=data.get("reason"), bypass_decision=None, created=float(data["created"]),
               updated=float(data["updated"]), started=data.get("started"), ended=data.get("ended"), exports=None,
               results_deleted=None, arena=data.get("arena"), needs=str(data.get("needs", "either")),
               placed=data.get("placed"), params=data.get("params"))


class RemoteRunner:
    """An :class:`~.runner.ArenaRunner` on a :class:`PortalLink`, with the heartbeat thread (module docstring)."""

    def __init__(self, link: PortalLink, settings: ArenaSettings) -> None:
        self.link = link
        service = cast(PortalService, link)  # PortalLink offers what ArenaRunner asks of its service
        self.runner = ArenaRunner(service, settings, poll_s=link.heartbeat_s,
                                  exports=NoExports(service))
        self.lost = 0
        self._beat = ServiceThread(self._heartbeat, "swarmdeck-runner-heartbeat", join_timeout=10.0)

    def start(self) -> RemoteRunner:
        self.runner.start()
        self._beat.start()
        return self

    def stop(self) -> None:
        self._beat.stop(10.0)
        self.runner.stop()
        self.link.close()

    def _heartbeat(self) -> None:
        while not self._beat.stopping:
            job = self.runner.current_job
            try:
                answer = self.link.heartbeat(job)
                if job is not None:
                    if answer["end_job"]:
                        self.runner.cancel(job)
                    if answer["stopped"]:
                        self.runner.emergency_stop()
                    self.link.send_recording(job)
            except LeaseLost:
                self.lost += 1
                if job is not None:
                    self.runner.cancel(job)
                self._reconnect()
            except (ClientError, OSError):
                pass  # the portal is away for a moment: the lease decides
            self._beat.wait(self.link.heartbeat_s)

    def _reconnect(self) -> None:
        while not self._beat.stopping:
            try:
                self.link.connect()
                return
            except ClientError:
                self._beat.wait(self.link.heartbeat_s)


def run_remote(url: str, token: str, arena: str, work: Path, config: PortalConfig, settings: ArenaSettings,
               stop: threading.Event, on_connect: Callable[[dict[str, Any]], None] | None = None) -> int:
    """Connect, run the arena's jobs until ``stop`` is set; 0. ClientError when the first connect fails."""
    link = PortalLink(url, token, arena, work, config)
    link.connect()
    spec = link.spec
    if on_connect is not None:
        on_connect(spec)
    settings = replace(settings, fleet=int(spec["robots"]), name=arena)
    runner = RemoteRunner(link, settings).start()
    try:
        while not stop.wait(1.0):
            pass
    finally:
        runner.stop()
    return 0

