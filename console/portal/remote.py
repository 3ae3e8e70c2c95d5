"""Remote arena runners, the portal's side: an arena on another machine (``--arena NAME=remote,...``) whose runner
(``swarmdeck runner --portal URL --arena NAME --token T``, :mod:`.remote_runner`) pulls its jobs and pushes their
results over authenticated HTTP (the routes: :mod:`.remote_api`).

Rules (:class:`RemoteArenas`):

* **Lease**: a runner connects for an arena and gets a lease (a random string) — unless another runner holds
  that arena and was heard from within ``PortalConfig.runner_lease_s`` (409 naming it). Every call carries the
  lease; one that is not the arena's current lease is 409 (a runner that lost its arena must stop).
* **Claims**: the runner asks which job the plan puts on its arena now (:meth:`~.service.PortalService.next_for`),
  checks its robots, then claims exactly that job (the conditional transition: a job runs on exactly one arena);
  the job records the lease that holds it (``holder``).
* **Results** (the recording while it is written, in pieces by offset; ``script.log``; ``run.json``) and the
  job's end are accepted only from the lease that holds the job and only while it is on the arena: a runner that
  reconnects with a stale job, or sends results for a job it does not hold, gets 409 and changes nothing.
* **A runner that dies** (kill -9, a cut cable): once its lease is ``runner_lease_s`` old, :meth:`expire` (the
  :class:`LeaseReaper` thread) marks its jobs ``interrupted``, recovers the partial recording the portal
  received (:func:`~.runner.recover_recordings`) and frees the arena for a runner that connects again.
* Cancels and emergency stops reach the runner in the answer to its heartbeat (every ``heartbeat_s``).
"""
from __future__ import annotations

import io
import secrets
import time
import zipfile
from pathlib import Path
from typing import Any

from swarmdeck.console.portal.accounts import User
from swarmdeck.console.portal.db import TransitionConflict
from swarmdeck.console.portal.errors import BadInput, Conflict
from swarmdeck.console.portal.exports import JobExports
from swarmdeck.console.portal.files import private_file
from swarmdeck.console.portal.runner import recover_recordings
from swarmdeck.console.portal.service import PortalService
from swarmdeck.console.portal.states import ACTIVE, JobState
from swarmdeck.core.service_thread import ServiceThread

#: what a runner may upload for the job it holds
UPLOADS = ("recording.mcap", "script.log", "run.json")
#: the largest piece of one upload, bytes
MAX_PIECE = 8 << 20
#: how often a runner says it is alive, s (well inside the lease)
HEARTBEAT_S = 1.0


class RemoteArenas:
    """The rules of the module docstring over a :class:`~.service.PortalService`. ``exports``: where ended jobs'
    exports are written (the server's; None: none)."""

    def __init__(self, service: PortalService, exports: JobExports | None = None) -> None:
        self.service, self.exports = service, exports

    # ------------------------------------------------------------------ leases
    def connect(self, user: User, arena: str) -> dict[str, Any]:
        """A runner takes ``arena``: its lease and what it needs to run jobs there."""
        svc = self.service
        svc._require_operator(user)
        spec = svc._spec(arena)
        if not spec.remote:
            raise BadInput(f"arena {arena!r} runs inside the portal (--arena {arena}=remote,... for a remote runner)",
                           "arena")
        now = time.time()
        expired = self.expire(now)
        with svc.store.transaction() as tx:
            held = svc.lab.lease(arena, tx)
            if held is not None and now - held[1] <= svc.config.runner_lease_s:
                raise Conflict(f"arena {arena!r} is held by another runner (heard from {now - held[1]:.1f} s ago); "
                               f"it is free {svc.config.runner_lease_s:g} s after that runner goes silent", "arena")
            lease = secrets.token_urlsafe(18)
            svc.lab.take_lease(tx, arena, lease, now)
            svc.accounts.audit(user, f"runner connected for arena {arena}", tx=tx)
        svc.notify()
        cfg = svc.config
        return {"lease": lease, "arena": spec.to_dict(), "lease_s": cfg.runner_lease_s, "heartbeat_s": HEARTBEAT_S,
                "grace_s": cfg.grace_s, "tick_budget_s": cfg.arena_tick_budget_s, "interrupted": expired}

    def _check(self, arena: str, lease: str) -> None:
        now = time.time()
        if not isinstance(lease, str) or not self.service.lab.touch(arena, lease, now,
                                                                    now - self.service.config.runner_lease_s):
            raise Conflict(f"this runner no longer holds arena {arena!r} (its lease ended): stop and connect again",
                           "lease")

    def _holds(self, arena: str, lease: str, job_id: int) -> None:
        self._check(arena, lease)
        if self.service.store.holder_of(job_id) != lease or self.service.job_state(job_id) not in ACTIVE:
            raise Conflict(f"job {job_id} is not on arena {arena!r} held by this runner (state "
                           f"{self.service.job_state(job_id)})", "job")

    def expire(self, now: float | None = None) -> list[int]:
        """Jobs of remote runners silent for longer than the lease: ``interrupted``, partial recordings recovered.
        Their ids."""
        svc = self.service
        now = time.time() if now is None else now
        ids: list[int] = []
        for spec in svc.config.arena_specs():
            held = svc.lab.lease(spec.name) if spec.remote else None
            if held is None or now - held[1] <= svc.config.runner_lease_s:
                continue
            with svc.store.transaction() as tx:
                for job_id in svc.store.held_by(held[0], tx):
                    try:
                        svc.store.transition(tx, job_id, JobState.INTERRUPTED, sources=ACTIVE, ended=now,
                                             reason=f"the runner of arena {spec.name} stopped answering during the "
                                                    "run (partial recording kept)")
                    except TransitionConflict:
                        continue
                    svc._event(tx, job_id, "ended")
                    ids.append(job_id)
        if ids:
            if self.exports is not None:
                recover_recordings(svc, self.exports, ids)
            svc.notify()
        return ids

    # ------------------------------------------------------------------ jobs
    def heartbeat(self, user: User, arena: str, lease: str, job_id: int | None) -> dict[str, Any]:
        """The runner is alive; whether its arena is stopped and whether its job must end now."""
        self.service._require_operator(user)
        self._check(arena, lease)
        end = False
        if job_id is not None:
            end = (self.service.store.holder_of(job_id) != lease or self.service.job_state(job_id) not in ACTIVE)
        return {"stopped": self.service._stopped(arena), "end_job": end,
                "state": None if job_id is None else self.service.job_state(job_id)}

    def claim(self, user: User, arena: str, lease: str, job_id: int | None, wait: str | None) -> dict[str, Any]:
        """``job_id`` None: the job the plan puts on ``arena`` now (not claimed: the runner checks its robots).
        With ``job_id``: claim exactly that job (None when it is no longer first), or — ``wait`` — say why it waits."""
        svc = self.service
        svc._require_operator(user)
        self._check(arena, lease)
        if svc._stopped(arena):
            return {"job": None, "stopped": True}
        if job_id is None:
            job = svc.next_for(arena)
            return {"job": None if job is None else job.to_dict(), "stopped": False, "claimed": False}
        if wait is not None:
            if svc.store.set_waiting_reason(job_id, str(wait)[:4000]):
                svc.notify()
            return {"job": None, "stopped": False, "claimed": False}
        job = svc.claim_for_arena(arena=arena, holder=lease, only=job_id)
        return {"job": None if job is None else job.to_dict(), "stopped": False, "claimed": job is not None}

    def script(self, user: User, arena: str, lease: str, job_id: int) -> bytes:
        """The job's files (``script.py`` or ``src/``) and its kind/entry as a zip, for the runner's sandbox."""
        self.service._require_operator(user)
        self._holds(arena, lease, job_id)
        folder = self.service.job_dir(job_id)
        buf = io.BytesIO()
        with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
            for path in sorted(folder.rglob("*")):
                rel = path.relative_to(folder).as_posix()
                if path.is_file() and (rel == "script.py" or rel.startswith("src/")):
                    z.write(path, rel)
        return buf.getvalue()

    def running(self, user: User, arena: str, lease: str, job_id: int) -> bool:
        self.service._require_operator(user)
        self._holds(arena, lease, job_id)
        return self.service.mark_running(job_id)

    def upload(self, user: User, arena: str, lease: str, job_id: int, name: str, offset: int, data: bytes) -> int:
        """Write ``data`` at ``offset`` of the job's result file ``name`` (0: from scratch); the file's size now.
        409 when ``offset`` is not the size the portal has (the runner resends from there)."""
        self.service._require_operator(user)
        self._holds(arena, lease, job_id)
        if name not in UPLOADS:
            raise BadInput(f"a runner uploads {', '.join(UPLOADS)}, not {name[:40]!r}", "name")
        if isinstance(offset, bool) or not isinstance(offset, int) or offset < 0:
            raise BadInput(f"offset must be an integer >= 0, got {offset!r}", "offset")
        if len(data) > MAX_PIECE:
            raise BadInput(f"send at most {MAX_PIECE} bytes at once", "data")
        path: Path = self.service.job_dir(job_id) / name
        size = path.stat().st_size if path.is_file() else 0
        if offset not in (0, size):
            raise Conflict(f"{name} has {size} bytes here: send from offset {size}", "offset")
        private_file(path)
        with open(path, "r+b" if offset else "wb") as f:
            f.seek(offset)
            f.write(data)
            f.truncate()
        return offset + len(data)

    def finish(self, user: User, arena: str, lease: str, job_id: int, state: str, reason: str | None) -> str | None:
        """End the held job (``done`` | ``failed`` | ``cancelled``); its exports are written here. Its final state."""
        svc = self.service
        svc._require_operator(user)
        self._holds(arena, lease, job_id)
        if state not in (JobState.DONE, JobState.FAILED, JobState.CANCELLED):
            raise BadInput(f"a run ends done, failed or cancelled, not {state!r}", "state")
        final = svc.finish_run(job_id, JobState(state), None if reason is None else str(reason)[:4000])
        if self.exports is not None and (svc.job_dir(job_id) / "recording.mcap").is_file():
            self.exports.submit(job_id)
        return None if final is None else str(final)

    def attention(self, user: User, arena: str, lease: str, message: str) -> None:
        """The remote arena cannot look after itself: it stops until an operator releases it."""
        svc = self.service
        svc._require_operator(user)
        self._check(arena, lease)
        with svc.store.transaction() as tx:
            svc.store.set_arena_stopped_named(tx, arena, True)
            svc.accounts.audit(None, f"arena {arena} needs an operator", None, str(message)[:1000], tx=tx)
        svc.notify()


class LeaseReaper:
    """The thread that calls :meth:`RemoteArenas.expire` every ``period_s``: :meth:`start`, :meth:`stop`."""

    def __init__(self, remote: RemoteArenas, *, period_s: float = 1.0) -> None:
        self.remote, self.period_s = remote, float(period_s)
        self.errors = 0
        self._thread = ServiceThread(self._run, "swarmdeck-portal-leases", join_timeout=10.0)

    def start(self) -> LeaseReaper:
        self._thread.start()
        return self

    def stop(self, timeout: float = 10.0) -> None:
        self._thread.stop(timeout)

    def _run(self) -> None:
        while not self._thread.stopping:
            try:
                self.remote.expire()
            except Exception:  # noqa: BLE001 - a busy database or a disk error: try again next period
                self.errors += 1
            self._thread.wait(self.period_s)
