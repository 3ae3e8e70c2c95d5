"""The portal's rules, in one place: submissions, who sees what, the queue, operator actions, the arena's latch.

The rules only: the jobs' rows (every SQL statement, rows as typed :class:`~.job.Job`) are the job store's
(:mod:`.jobstore`), a job's folder (layout, results, reports, the video) is :mod:`.jobfiles`'.

The HTTP routes (:mod:`.api`, and the pages) are thin: each calls one method
of :class:`PortalService` with the signed-in :class:`~.accounts.User` and turns
its :class:`~.errors.PortalError` into a JSON error. The verification workers
(:mod:`.workers`) and the arena runner (:mod:`.runner`) move jobs through the
state machine of :mod:`.db` with the ``claim_*``/``finish_*`` methods here.

Rules:

* **Visibility**: a researcher sees, cancels and downloads only their own jobs;
  any other job id is :class:`~.errors.NotFound` (404), exactly as a job that
  does not exist. Operators see every job.
* **Submission** (:meth:`PortalService.submit`): the manifest and upload checks
  of :mod:`.submission`; the job's files go to ``DIR/jobs/<id>/`` under names
  the portal chooses (``script.py``, or ``src/<checked member names>``); the job
  starts ``awaiting verification`` (the states: :mod:`.states`).
* **Approval**: verified jobs go ``awaiting approval → in arena queue`` at once unless an
  operator switched manual approval on (:meth:`PortalService.set_manual_approval`);
  then an operator approves each. Switching it off releases the jobs awaiting approval.
* **Queue order**: jobs ``in arena queue`` run by ``priority`` then id;
  :meth:`PortalService.move` puts a job at a position. Queued jobs are verified
  round-robin across researchers (:meth:`PortalService.claim_for_verification`).
* **Barrier bypass**: a run goes without the barrier only if verification
  said "may bypass", the manifest asked for it (``no_barrier``), no operator
  forbade it (:meth:`PortalService.forbid_barrier`) *and an operator approved that
  job's bypass* (:meth:`PortalService.decide_bypass`, audited) —
  :meth:`PortalService.bypass_allowed`. Such a job stays ``awaiting approval`` with the reason
  :data:`BYPASS_WAIT` until an operator approves the bypass (→ ``in arena queue``, to run
  without the barrier, with the guard) or refuses it (→ it runs with the barrier),
  whatever the manual-approval switch says: a verdict alone never removes protection.
* **Emergency stop** (:meth:`PortalService.emergency_stop`): the arena runner
  stops the robots now and ends the running job (``cancelled``, reason "emergency
  stop"); the arena stays stopped (no job starts) until an operator releases it
  (:meth:`PortalService.release_arena`). The latch is in the database, so it
  survives a restart.
* Every operator action is in the audit log, committed with the change itself.
* **Limits** (:mod:`.quotas`, ``PortalConfig.quotas``): a researcher's submission over their unfinished-jobs
  or daily verification-CPU limit is 429, over their disk quota 403, each naming the limit and the current
  value; the verification workers charge each job's CPU (:meth:`PortalService.record_verification_cpu`).
* **Retention** (``PortalConfig.retain_days``): :meth:`PortalService.sweep_results` deletes the folders of
  jobs that ended long ago; the row stays with ``results_deleted`` and its downloads say why they are gone.
* **Ids** from outside are checked (:func:`~.job.valid_id`): one SQLite cannot hold is "no job" (404), never a 500.

Result files (:meth:`PortalService.files`): a fixed list of names
(:data:`~.jobfiles.RESULT_FILES`) under the job's folder; a download names one of them,
never a path.
"""
from __future__ import annotations

import json
import math
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

from swarmdeck.console.portal.accounts import Accounts, User
from swarmdeck.console.portal.arenas import DEFAULT_ARENA, ArenaSpec, check_request
from swarmdeck.console.portal.compare import RunCache, compare_recordings
from swarmdeck.console.portal.db import Database, TransitionConflict
from swarmdeck.console.portal.errors import BadInput, Conflict, Forbidden, NotFound, Unavailable
from swarmdeck.console.portal.job import (
    BYPASS_VERDICT,
    BYPASS_WAIT,
    REJECTED_VERDICT,
    BypassDecision,
    ExportState,
    Job,
    bypass_decided,
)
from swarmdeck.console.portal.jobfiles import RESULT_FILES, JobFiles, ResultFile
from swarmdeck.console.portal.jobstore import PRE_QUEUE, JobStore, JobStoreAPI
from swarmdeck.console.portal.labstore import LabStore, Reservation
from swarmdeck.console.portal.notify import SmtpSettings, check_email, check_webhook
from swarmdeck.console.portal.quotas import DAY_S, Quotas, check_counts, check_disk
from swarmdeck.console.portal.quotas import usage as quota_usage
from swarmdeck.console.portal.results import results_summary
from swarmdeck.console.portal.scheduler import (
    OVERHEAD_RUNS,
    Lane,
    Pending,
    Placement,
    Window,
    occupancy,
    overhead,
    plan,
)
from swarmdeck.console.portal.states import ACTIVE, FINAL, JobState
from swarmdeck.console.portal.submission import (
    Limits,
    Manifest,
    Upload,
    check_bundle,
    check_declared,
    check_upload,
    parse_manifest,
    parse_params,
)
from swarmdeck.console.portal.submission import display_name as _display_name
from swarmdeck.console.sandbox.bundle import ScriptBundle
from swarmdeck.console.sandbox.confinement import JailConfig, SandboxLimits
from swarmdeck.console.sandbox.script_env import ScriptEnv, listing
from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds

__all__ = ["BYPASS_VERDICT", "BYPASS_WAIT", "RESULT_FILES", "ArenaControl", "ArenaReports", "ArenaState", "PortalConfig",
           "PortalService"]


class ArenaControl(Protocol):
    """What the service asks of the arena runner (:class:`~.runner.ArenaRunner`)."""

    def emergency_stop(self) -> None: ...

    def cancel(self, job_id: int) -> None: ...


@runtime_checkable
class ArenaReports(Protocol):
    """What an arena runner that reports on itself offers the pages (:class:`~.runner.ArenaRunner` does)."""

    def live_log(self, job_id: int) -> bytes | None:
        """The script output of job ``job_id`` so far while it runs on the arena (None otherwise)."""
        ...

    def alerts(self) -> dict[str, Any]:
        """The running (or last) job's guard and contact events: ``{"job", "messages"}``."""
        ...

    def fleet_status(self) -> dict[str, Any]:
        """The fleet table: each robot docked/charging/assigned/away, its charge."""
        ...


@dataclass(frozen=True)
class PortalConfig:
    """The service's settings.

    Attributes:
        data: the data folder (database, ``jobs/<id>/``).
        limits: what a submission may be (fleet size, maximum duration, upload sizes).
        verify_runs: verification runs per job (each without and with the barrier).
        verify_epsilon: the largest bound on P(contact per run) (at ``verify_confidence``, from the raw runs,
            REFERENCE.md §17) a job's bypass may have; above it the bypass is refused with the bound (None: the
            bound is stated in the report, not required).
        verify_confidence: the confidence of that bound, in (0, 1).
        verify_falsify_budget: runs per job the falsifier may spend searching the set-up tolerance for the run
            closest to a contact (``VerificationConfig.falsify_budget``; 0: no search); the worst case's recording
            is the job's ``worst-case.mcap``, a contact found refuses the bypass.
        verify_seed: base seed of verification (job i uses ``verify_seed + i``).
        tick_budget_s: the script's per-tick compute budget in verification (and on the ``--fast`` simulated
            arena, where nothing waits in real time), wall s.
        arena_tick_budget_s: the script's per-tick compute budget on the real-time arena, wall s (None: one
            control period, 0.033 s — the script's commands for a tick are due before the next tick, as in the
            paper's 30 Hz loop). A tick without them stops the robots for that tick (zero commands).
        arena_overrun_s: on the real-time arena, missed ticks in a row for this long (s of control periods)
            end the run (``overruns``); a few missed ticks only stop the robots for those ticks.
        grace_s: the arena run's time limit is the declared duration plus this, s.
        trusted: run scripts unconfined where this machine cannot confine them.
        allow_no_cgroup: run scripts even where no cgroup can be created per run (``--allow-no-cgroup``).
        quotas: per-researcher limits (:mod:`.quotas`): unfinished jobs, verification CPU a day, results on disk.
        script_env: the lab's script environment (``--script-env PATH``): what users' scripts may import
            (:mod:`swarmdeck.console.sandbox.script_env`); None: what swarmdeck's own environment has.
        retain_days: results of jobs that ended more than this many days ago are deleted by
            :meth:`PortalService.sweep_results` (the job's row stays, with ``results_deleted``); None: kept.
        arenas: the arenas behind the portal (:mod:`.arenas`; ``--arena NAME=SPEC``); empty: one.
        smtp: the SMTP server notifications by e-mail go through (:mod:`.notify`); None: no e-mail.
        runner_lease_s: a remote runner not heard from for this long has lost its arena; its job is interrupted.
    """

    data: Path
    limits: Limits = field(default_factory=Limits)
    verify_runs: int = 4
    verify_epsilon: float | None = None
    verify_confidence: float = 0.95
    verify_falsify_budget: int = 0
    verify_seed: int = 0
    tick_budget_s: float = 1.0
    arena_tick_budget_s: float | None = None
    arena_overrun_s: float = 1.0
    grace_s: float = 15.0
    trusted: bool = False
    allow_no_cgroup: bool = False
    quotas: Quotas = field(default_factory=Quotas)
    retain_days: float | None = None
    script_env: str | None = None
    arenas: tuple[ArenaSpec, ...] = ()
    smtp: SmtpSettings | None = None
    runner_lease_s: float = 20.0

    def arena_specs(self) -> tuple[ArenaSpec, ...]:
        """The arenas behind the portal (``--arena``); without any, one simulated arena of ``limits.fleet`` robots
        named :data:`~.arenas.DEFAULT_ARENA`."""
        return self.arenas or (ArenaSpec(DEFAULT_ARENA, robots=self.limits.fleet),)

    def jail(self) -> JailConfig:
        """The jail every verification and arena run uses (``allow_no_cgroup``, ``script_env``)."""
        return JailConfig(allow_no_cgroup=self.allow_no_cgroup, script_env=self.script_env)

    def arena_budget(self, dt: float, real_time: bool) -> tuple[float, int]:
        """(per-tick compute budget s, missed ticks in a row that end the run) of a script on the arena with
        control period ``dt`` s (see the attributes)."""
        if not real_time:
            return self.tick_budget_s, SandboxLimits().max_overruns
        budget = float(dt) if self.arena_tick_budget_s is None else float(self.arena_tick_budget_s)
        return budget, max(1, math.ceil(self.arena_overrun_s / budget - 1e-9))


@dataclass(frozen=True)
class ArenaState:
    """The arena as operators see it (:meth:`PortalService.arena_state`).

    ``needs_operator``: why the arena stopped itself (None: it did not); ``alerts``: the running or last job's
    bypass revocation and contacts (:meth:`.ArenaRunner.alerts`); ``fleet``: the fleet table
    (:meth:`.ArenaFleet.status`; None without a fleet)."""

    stopped: bool
    needs_operator: str | None
    alerts: dict[str, Any] | None
    manual_approval: bool
    running: Job | None
    queue: tuple[Job, ...]
    fleet: dict[str, Any] | None
    arenas: tuple[dict[str, Any], ...] = ()

    def to_dict(self) -> dict[str, Any]:
        return {"stopped": self.stopped, "needs_operator": self.needs_operator, "alerts": self.alerts,
                "manual_approval": self.manual_approval,
                "running": None if self.running is None else self.running.to_dict(),
                "queue": [j.to_dict() for j in self.queue], "fleet": self.fleet, "arenas": list(self.arenas)}


class PortalService:
    """The rules (module docstring) over the :class:`.JobStore`, the :class:`.JobFiles` and :class:`.Accounts`."""

    def __init__(self, config: PortalConfig, *, db: Database | None = None, accounts: Accounts | None = None) -> None:
        self.config = config
        self.data = Path(config.data)
        self.db = db if db is not None else Database(self.data)
        self.accounts = accounts if accounts is not None else Accounts(self.db)
        self.store: JobStoreAPI = JobStore(self.db)  # the one interface to the jobs' rows (JobStoreAPI)
        self.job_files = JobFiles(self.data / "jobs")  # the data folder itself is made 0700 by the Database
        self.changed = threading.Condition()  # notified after every change workers/runner/live views wait on
        self.arena: ArenaControl | None = None
        self.lab = LabStore(self.db)  # reservations, notifications, remote runners' leases
        self.run_cache = RunCache()  # job comparisons: the metrics and tracks of recordings read lately
        self.runners: dict[str, ArenaControl] = {}  # arena name -> its in-process runner (several arenas)
        self.remote: object | None = None  # the remote runners' rules (.remote.RemoteArenas), made by the API

    # ------------------------------------------------------------------ helpers
    def job_dir(self, job_id: int) -> Path:
        """The job's folder (:meth:`.JobFiles.folder`)."""
        return self.job_files.folder(job_id)

    def notify(self) -> None:
        with self.changed:
            self.changed.notify_all()

    def wait_for_change(self, timeout: float) -> None:
        """Block until something changed (or ``timeout`` s passed; other processes' changes are seen by polling)."""
        with self.changed:
            self.changed.wait(timeout)

    def _visible(self, user: User, job_id: int) -> Job:
        """The job if ``user`` may see it; NotFound (404) for another researcher's job, as for no job."""
        job = self.store.get(job_id)
        if job is None or (not user.is_operator and job.user_id != user.id):
            raise NotFound(f"no job {job_id}", "job")
        return job

    @staticmethod
    def _require_operator(user: User) -> None:
        if not user.is_operator:
            raise Forbidden("this needs an operator account", "Authorization")

    def _require_results(self, job: Job) -> None:
        """NotFound when the retention sweep deleted the job's results (saying when and why)."""
        if job.results_deleted is not None:
            days = "" if self.config.retain_days is None else f" (the lab keeps results {self.config.retain_days:g} days)"
            raise NotFound(f"job {job.id}'s results were deleted on "
                           f"{time.strftime('%Y-%m-%d', time.gmtime(job.results_deleted))}{days}", "job")

    # ------------------------------------------------------------------ researchers
    def submit(self, user: User, filename: str | None, data: bytes, manifest: Any = None,
               entry: str | None = None) -> Job:
        """Check and store a submission; the new job (``awaiting verification``). ``manifest``: JSON text or
        object, or None to use ``manifest.json`` from inside a ``.zip``; ``entry``: the script to run inside a
        ``.zip`` (overrides the manifest's ``entry``)."""
        upload = check_upload(filename, data, self.config.limits)
        if manifest is None or (isinstance(manifest, str) and not manifest.strip()):
            if upload.manifest is None:
                raise BadInput("send a manifest (name, robots, duration) with the script", "manifest")
            manifest = upload.manifest
        if entry is not None and str(entry).strip():
            if upload.kind != "zip":
                raise BadInput("an entry file is only for a .zip (a .py is its own entry)", "entry")
            if isinstance(manifest, (str, bytes)):
                try:
                    manifest = json.loads(manifest)
                except ValueError:
                    pass  # parse_manifest says what is wrong with it
            if isinstance(manifest, dict):
                manifest = {**manifest, "entry": str(entry).strip()}
        m = parse_manifest(manifest, self.config.limits)
        check_request(self.config.arena_specs(), m.robots, m.needs, m.arena)
        entry = self._entry(m, upload)
        if m.params is not None:  # names the script declares, values of their kinds
            check_declared(self._bundle(upload, entry), m.params)
        return self._admit(user, upload, m, entry, initial_poses=m.initial_poses, no_barrier=m.no_barrier,
                           arena=m.arena, needs=m.needs, params=None if m.params is None else dict(m.params))

    @staticmethod
    def _bundle(upload: Upload, entry: str) -> ScriptBundle:
        try:
            return ScriptBundle.from_files(upload.files, entry)
        except ValueError as exc:
            raise BadInput(str(exc), "script") from None

    def _admit(self, user: User, upload: Upload, m: Manifest, entry: str, *,
               then: Callable[[Any, int], None] | None = None, **fields: Any) -> Job:
        """Store a checked submission as a new job: the researcher's disk, job-count and daily CPU limits checked
        (operators are exempt), the row (``fields``: the store's insert columns beyond the manifest's), ``then(tx,
        job_id)`` and the job's files in one transaction (no job row without its files); the queue is woken."""
        if not user.is_operator:
            check_disk(self.store.kept_job_ids(user.id), self.config.quotas, self.job_files.root)
        now = time.time()
        with self.store.transaction() as tx:
            if not user.is_operator:
                check_counts(self.config.quotas, self.store.unfinished_count(user.id, tx),
                             self.store.verification_cpu(user.id, now - DAY_S, tx), now)
            job_id = self.store.insert(tx, user_id=user.id, name=m.name, kind=upload.kind, script=upload.display_name,
                                       entry=entry, robots=m.robots, duration=m.duration, now=now, **fields)
            if then is not None:
                then(tx, job_id)
            self.job_files.store(job_id, upload, m, entry)
        self.notify()
        return self.job(user, job_id)

    def submit_sweep(self, user: User, filename: str | None, data: bytes, sweep: Any, entry: str | None = None) -> Job:
        """Check and store a sweep (:mod:`.sweep_job`): ONE job, ``awaiting verification``, whose runs go to the
        verification executors and which never enters the arena queue. ``sweep``: the request (JSON text or object);
        the CLI's refusals (undeclared parameter, empty range, too many points) are 422 with its messages."""
        from swarmdeck.console.portal.sweep_job import check_sweep, parse_request

        upload = check_upload(filename, data, self.config.limits)
        request = parse_request(sweep, self.config.limits, _display_name(upload.display_name).rsplit('.', 1)[0] or 'sweep')
        if entry is not None and str(entry).strip() and upload.kind != "zip":
            raise BadInput("an entry file is only for a .zip (a .py is its own entry)", "entry")
        m = Manifest(request.name, max(request.counts), request.duration,
                     entry=str(entry).strip() if entry is not None and str(entry).strip() else None,
                     needs="simulated")
        entry = self._entry(m, upload)
        check_sweep(request, self._bundle(upload, entry))
        if request.promote is not None:  # its best point must be able to run on an arena of this portal
            check_request(self.config.arena_specs(), max(request.counts), "either", None)
        return self._admit(user, upload, m, entry, initial_poses=None, no_barrier=False, needs="simulated",
                           then=lambda tx, job_id: self.store.set_sweep(tx, job_id, request.to_dict()))

    def finish_sweep(self, job_id: int, ok: bool, reason: str | None) -> None:
        """A sweep job's runs ended: ``done`` (every run finished; a run whose script failed is a row of the table)
        or ``failed`` with the reason (the sweep could not run). A job cancelled meanwhile stays cancelled."""
        with self.store.transaction() as tx:
            try:
                self.store.transition(tx, job_id, JobState.DONE if ok else JobState.FAILED,
                                      sources=(JobState.VERIFYING,), ended=time.time(),
                                      reason=None if reason is None else reason[:4000])
            except TransitionConflict:
                return
            self._event(tx, job_id, "ended")
        self.notify()

    def promote(self, sweep_job: Job, params: dict[str, Any] | None, robots: int, duration: float,
                name: str) -> Job:
        """Submit a sweep's best point as a normal arena job of the sweep's owner (issue 31.2): the sweep's stored
        script, ``params`` (the point's values; None: the defaults), ``robots``, ``duration``; ``origin`` names the
        sweep. It is verified and queued like any job; the owner's limits apply (QuotaExceeded), and BadInput when
        no arena can run it or the owner's account is disabled."""
        user = self.accounts.user_named(sweep_job.owner)
        if user.disabled:
            raise BadInput(f"{user.name}'s account is disabled", "promote")
        path, entry = self.script(sweep_job)
        if sweep_job.kind == "py":
            files, entry = {"script.py": path.read_bytes()}, "script.py"
        else:
            files, entry = dict(ScriptBundle.from_path(path, entry).files), str(entry)
        upload = Upload(kind=sweep_job.kind, display_name=sweep_job.script, files=files, entry=entry)
        values = parse_params(params)  # the one check of a job's values, as for a submitted manifest
        m = Manifest(name[:100], int(robots), float(duration), entry=None if sweep_job.kind == "py" else entry,
                     params=values)
        check_request(self.config.arena_specs(), m.robots, m.needs, None)
        return self._admit(user, upload, m, entry, initial_poses=None, no_barrier=False, needs=m.needs,
                           params=params, origin=int(sweep_job.id))

    @staticmethod
    def _entry(m: Manifest, upload: Upload) -> str:
        if upload.kind == "py":
            return "script.py"
        entry = m.entry or upload.entry
        check_bundle(upload.files, entry)
        return str(entry)

    def script(self, job: Job) -> tuple[Path, str | None]:
        """What the sandbox runs for ``job`` (:meth:`.JobFiles.script`)."""
        return self.job_files.script(job)

    def jobs(self, user: User, *, mine: bool = False) -> list[Job]:
        """A researcher's own jobs; an operator's view of all jobs (``mine``: only their own). Newest first, the
        waiting ones with their estimated start and end (:meth:`with_eta`)."""
        return self.with_eta(self.store.list(None if user.is_operator and not mine else user.id))

    def job(self, user: User, job_id: int) -> Job:
        return self.with_eta([self._visible(user, job_id)])[0]

    def cancel(self, user: User, job_id: int) -> Job:
        """Cancel a job that has not ended (its owner, or an operator); 409 if it has ended."""
        job = self._visible(user, job_id)
        with self.store.transaction() as tx:
            try:
                self.store.transition(tx, job.id, JobState.CANCELLED, ended=time.time(),
                                      reason=f"cancelled by {user.name}")
            except TransitionConflict as exc:
                if exc.state in FINAL:
                    raise Conflict(f"job {job_id} has already ended ({exc.state}): there is nothing to cancel",
                                   "job") from None
                raise Conflict(str(exc), "job") from None
            if user.is_operator and job.user_id != user.id:
                self.accounts.audit(user, "cancel", job.id, tx=tx)
            self._event(tx, job.id, "ended")
        if job.state in ACTIVE:
            for control in self._controls():
                control.cancel(job.id)
        self.notify()
        return self.job(user, job_id)

    def report(self, user: User, job_id: int) -> dict[str, Any]:
        """The verification report (JSON) of a job; 404 until verification has finished."""
        job = self._visible(user, job_id)
        self._require_results(job)
        report = self.job_files.report(job.id)
        if report is None:
            raise NotFound(f"job {job_id} has no verification report yet", "job")
        return report

    def run_summary(self, user: User, job_id: int) -> dict[str, Any] | None:
        """How the arena run went (``run.json``: how it ended, the robots' set-up and return), None before
        it ended (or when the file cannot be read)."""
        return self.job_files.run_summary(self._visible(user, job_id).id)

    def results(self, user: User, job_id: int) -> dict[str, Any]:
        """The results summary of an ended job (:func:`.results.results_summary`); 404 while it has not ended."""
        job = self._visible(user, job_id)
        if job.state not in FINAL:
            raise NotFound(f"job {job_id} is {job.state}: its results come when it has ended", "job")
        summary = results_summary(job.to_dict(), self.job_files.run_summary(job.id),
                                  [f.to_dict() for f in self.job_files.listing(job.id)])
        if job.sweep is not None:  # a sweep job: its table in short (sweep_job.results)
            from swarmdeck.console.portal.sweep_job import results as sweep_results

            summary["sweep"] = sweep_results(self.job_dir(job.id))
        return summary

    def compare(self, user: User, job_id: int, other_id: int) -> dict[str, Any]:
        """Job ``job_id`` compared with job ``other_id`` (:func:`.compare.compare_recordings`: the metric table,
        what differs, both runs' tracks). Both must be visible to ``user`` (a researcher's own: another
        researcher's job is 404, as everywhere), ended, with their results kept and a recording."""
        from swarmdeck.console.portal.jobfiles import RECORDING

        if job_id == other_id:
            raise BadInput(f"compare job {job_id} with another job, not with itself", "with")
        jobs = [self._visible(user, j) for j in (job_id, other_id)]
        paths = []
        for job in jobs:
            if job.state not in FINAL:
                raise NotFound(f"job {job.id} is {job.state}: it can be compared when it has ended", "job")
            self._require_results(job)
            paths.append(self.job_files.path(job, RECORDING))
        return compare_recordings(paths, [f"job {j.id}" for j in jobs], self.run_cache)

    def script_log(self, user: User, job_id: int, since: int = 0) -> dict[str, Any]:
        """The job's script output from byte ``since`` on: ``{"text", "next", "live"}`` — while it runs, what the
        script printed so far (the arena runner's live copy); after, ``script.log``. Its owner and operators."""
        job = self._visible(user, job_id)
        if isinstance(since, bool) or not isinstance(since, int) or since < 0:
            raise BadInput(f"since must be an integer >= 0, got {since!r}", "since")
        arena = self.arena  # the runner's copy of the output until script.log is written
        data = arena.live_log(job.id) if isinstance(arena, ArenaReports) else None
        if data is None:
            self._require_results(job)
            data = self.job_files.script_log(job.id)
        chunk = data[since:]
        return {"text": chunk.decode("utf-8", errors="replace"), "next": since + len(chunk),
                "live": job.state in ACTIVE}

    def files(self, user: User, job_id: int) -> list[ResultFile]:
        """The job's result files that exist (:meth:`.JobFiles.listing`)."""
        return self.job_files.listing(self._visible(user, job_id).id)

    def downloads(self, user: User, job_id: int) -> list[ResultFile]:
        """What the job page offers: its result files, and the video if it can be made on its first request."""
        job = self._visible(user, job_id)
        listed = self.job_files.listing(job.id)
        video = None if job.results_deleted is not None else self.job_files.video_to_come(job, listed)
        return listed if video is None else [*listed, video]

    def file_path(self, user: User, job_id: int, name: str) -> Path:
        """The path of result file ``name`` of the job (one of :data:`RESULT_FILES`); 404 otherwise, 503 while
        its export is written. ``video.mp4`` is made from the recording on its first request (:meth:`video`)."""
        job = self._visible(user, job_id)
        if name in RESULT_FILES:
            self._require_results(job)
        return self.job_files.path(job, name)

    def video(self, user: User, job_id: int) -> Path:
        """The job's ``video.mp4`` (:meth:`.JobFiles.video`: made from the recording on the first request)."""
        job = self._visible(user, job_id)
        self._require_results(job)
        return self.job_files.video(job)

    # ------------------------------------------------------------------ quotas and retention
    def record_verification_cpu(self, job_id: int, cpu_s: float) -> None:
        """Charge ``cpu_s`` CPU seconds of verification to the job's owner (the daily limit, :mod:`.quotas`)."""
        if not (isinstance(cpu_s, (int, float)) and math.isfinite(cpu_s) and cpu_s >= 0):
            return
        self.store.record_verification_cpu(job_id, float(cpu_s))

    def environment(self) -> dict[str, Any]:
        """What scripts can import here (:func:`swarmdeck.console.sandbox.script_env.listing`), read now: packages
        the lab adds show at once. Unavailable when the configured environment no longer follows its rule."""
        try:
            env = None if self.config.script_env is None else ScriptEnv.open(self.config.script_env)
        except ValueError as exc:
            raise Unavailable(f"the lab's script environment is broken: {exc}") from None
        return listing(env)

    def usage(self, user: User) -> dict[str, Any]:
        """The researcher's use of each limit (:func:`.quotas.usage`; operators: limits None, not limited)."""
        return quota_usage(self.store.unfinished_count(user.id),
                           self.store.verification_cpu(user.id, time.time() - DAY_S),
                           self.store.kept_job_ids(user.id),
                           Quotas(None, None, None) if user.is_operator else self.config.quotas, self.job_files.root)

    def sweep_results(self, now: float | None = None) -> list[int]:
        """Delete the folders (script, recording, exports, logs, reports) of jobs that ended more than
        ``retain_days`` ago and whose exports are not being written; each job's row stays, with
        ``results_deleted`` set (shown on its page). The ids swept (none when ``retain_days`` is None)."""
        if self.config.retain_days is None:
            return []
        now = time.time() if now is None else float(now)
        swept = self.store.ended_before(now - float(self.config.retain_days) * DAY_S)
        for job_id in swept:
            self.job_files.delete(job_id)
            self.store.mark_results_deleted(job_id, now)
        if swept:
            self.notify()
        return swept

    # ------------------------------------------------------------------ operators
    def _operator_transition(self, user: User, job_id: int, target: JobState, action: str,
                             sources: tuple[JobState, ...] | None = None, detail: str = "", **columns: Any) -> Job:
        self._require_operator(user)
        job = self._visible(user, job_id)
        with self.store.transaction() as tx:
            try:
                self.store.transition(tx, job.id, target, sources=sources, **columns)
            except TransitionConflict as exc:
                raise Conflict(str(exc), "job") from None
            self.accounts.audit(user, action, job.id, detail, tx=tx)
        self.notify()
        return self.job(user, job_id)

    def approve(self, user: User, job_id: int) -> Job:
        """Manual approval: ``awaiting approval → in arena queue``. A job waiting for a decision on its barrier
        bypass is refused (409): approve or refuse the bypass (:meth:`decide_bypass`)."""
        self._require_operator(user)
        if self._visible(user, job_id).bypass_pending:
            raise Conflict(f"job {job_id} asks to run without the barrier: approve or refuse that bypass "
                           f"(POST /api/operator/jobs/{job_id}/bypass {{\"approve\": true|false}})", "job")
        return self._operator_transition(user, job_id, JobState.IN_ARENA_QUEUE, "approve",
                                         sources=(JobState.AWAITING_APPROVAL,))

    def decide_bypass(self, user: User, job_id: int, approve: bool) -> Job:
        """An operator's decision on a job's barrier bypass (module docstring), audited with the verdict and S.

        Approve: the job goes ``in arena queue`` and runs without the barrier, with the guard
        (:mod:`swarmdeck.safety.guard`). Refuse: it runs with the barrier (``in arena queue``, or still
        ``awaiting approval`` while manual approval is on). 409 unless the job is ``awaiting approval`` and waiting
        for this decision."""
        self._require_operator(user)
        if not isinstance(approve, bool):
            raise BadInput(f"approve must be true or false, got {approve!r}", "approve")
        job = self._visible(user, job_id)
        if job.state != JobState.AWAITING_APPROVAL or not job.bypass_pending:
            raise Conflict(f"job {job_id} is {job.state} and not waiting for a decision on running without the "
                           "barrier", "job")
        score = "n/a" if job.safety_score is None else f"{job.safety_score:.4f}"
        detail = f"verdict {job.verdict!r}, S = {score}"
        target = JobState.IN_ARENA_QUEUE if approve or not self.manual_approval else JobState.AWAITING_APPROVAL
        decision = BypassDecision.APPROVED if approve else BypassDecision.REFUSED
        with self.store.transaction() as tx:
            if target == JobState.AWAITING_APPROVAL:  # manual approval on: the refused job now waits for the usual approval
                if not self.store.decide_bypass_in_place(tx, job.id, decision, forbidden=not approve):
                    raise Conflict(f"job {job_id} is no longer awaiting approval", "job")
            else:
                try:
                    self.store.transition(tx, job.id, target, sources=(JobState.AWAITING_APPROVAL,),
                                          bypass_decision=decision, barrier_forbidden=int(not approve), reason=None)
                except TransitionConflict as exc:
                    raise Conflict(str(exc), "job") from None
            self.accounts.audit(user, "approve barrier bypass" if approve else "refuse barrier bypass", job.id,
                                detail, tx=tx)
        self.notify()
        return self.job(user, job_id)

    def hold(self, user: User, job_id: int) -> Job:
        """Hold a job awaiting verification or approval or in the arena queue (it keeps its place; :meth:`release`
        puts it back)."""
        self._require_operator(user)
        job = self._visible(user, job_id)
        return self._operator_transition(user, job_id, JobState.HELD, "hold", held_from=job.state)

    def release(self, user: User, job_id: int) -> Job:
        """Release a held job to the state it was held in (one awaiting approval to the arena queue if manual
        approval is off by now)."""
        self._require_operator(user)
        job = self._visible(user, job_id)
        if job.state != JobState.HELD:
            raise Conflict(f"job {job_id} is {job.state}, not held", "job")
        back = job.held_from or JobState.AWAITING_VERIFICATION
        if back == JobState.AWAITING_APPROVAL and not self.manual_approval and not job.bypass_pending:
            back = JobState.IN_ARENA_QUEUE  # manual approval was switched off while it was held
        return self._operator_transition(user, job_id, back, "release", sources=(JobState.HELD,), held_from=None)

    def operator_cancel(self, user: User, job_id: int) -> Job:
        self._require_operator(user)
        return self.cancel(user, job_id)

    def move(self, user: User, job_id: int, position: int) -> Job:
        """Put a job of the arena queue at ``position`` (0: next)."""
        self._require_operator(user)
        job = self._visible(user, job_id)
        if isinstance(position, bool) or not isinstance(position, int) or position < 0:
            raise BadInput(f"position must be an integer >= 0, got {position!r}", "position")
        with self.store.transaction() as tx:
            ids = self.store.queue_ids(tx)
            if job.id not in ids:
                raise Conflict(f"job {job_id} is {self.store.state_in(tx, job.id)}: only jobs in the arena queue can "
                               "be reordered", "job")
            ids.remove(job.id)
            ids.insert(min(position, len(ids)), job.id)
            self.store.reorder_queue(tx, ids)
            # counted from 1, as the operator page and the CLI show positions (the API's ``position`` is 0-based)
            self.accounts.audit(user, "move", job.id, f"to position {min(position, len(ids) - 1) + 1}", tx=tx)
        self.notify()
        return self.job(user, job_id)

    def forbid_barrier(self, user: User, job_id: int, forbid: bool) -> Job:
        """Forbid (or allow again) running this job without the barrier; refused once it is on the arena."""
        self._require_operator(user)
        job = self._visible(user, job_id)
        if not isinstance(forbid, bool):
            raise BadInput(f"forbid must be true or false, got {forbid!r}", "forbid")
        with self.store.transaction() as tx:
            if not self.store.set_barrier_forbidden(tx, job.id, forbid):
                raise Conflict(f"job {job_id} is {self.store.state_in(tx, job.id)}: the barrier can no longer be "
                               "changed", "job")
            self.accounts.audit(user, "forbid barrier bypass" if forbid else "allow barrier bypass", job.id, tx=tx)
            # a job waiting for the bypass decision that is now forbidden runs with the barrier; a waiting job whose
            # bypass is allowed again waits for an operator's decision on it
            if forbid and not self.manual_approval:
                self.store.requeue_bypass_wait(tx, job.id)
            elif not forbid:
                self.store.back_to_bypass_wait(tx, job.id)
        self.notify()
        return self.job(user, job_id)

    @property
    def manual_approval(self) -> bool:
        return self.store.manual_approval()

    def set_manual_approval(self, user: User, on: bool) -> dict[str, Any]:
        """Switch manual approval; switching it off sends every approved job to the arena queue."""
        self._require_operator(user)
        if not isinstance(on, bool):
            raise BadInput(f"manual_approval must be true or false, got {on!r}", "manual_approval")
        with self.store.transaction() as tx:
            self.store.set_manual_approval(tx, on)
            if not on:  # jobs waiting for a decision on their bypass keep waiting for it
                self.store.release_approved(tx)
            self.accounts.audit(user, "manual approval on" if on else "manual approval off", tx=tx)
        self.notify()
        return self.settings()

    def settings(self) -> dict[str, Any]:
        return {"manual_approval": self.manual_approval}

    @property
    def arena_stopped(self) -> bool:
        return self.store.arena_stopped()

    def emergency_stop(self, user: User, arena: str | None = None) -> ArenaState:
        """Stop the robots now, end the running job, latch the arena stopped (see the module docstring).
        ``arena``: only that arena (its robots, its jobs, its latch); None: every arena."""
        self._require_operator(user)
        spec = None if arena is None else self._spec(arena)
        with self.store.transaction() as tx:
            if spec is None:
                self.store.set_arena_stopped(tx, True)
                active = self.store.ids_in(tx, ACTIVE)
            else:
                self.store.set_arena_stopped_named(tx, spec.name, True)
                active = [j.id for j in self.store.active_on(spec.name, self._default, tx)]
            for job_id in active:
                self.store.transition(tx, job_id, JobState.CANCELLED, ended=time.time(),
                                      reason=f"emergency stop by operator {user.name}")
                self._event(tx, job_id, "ended")
            self.accounts.audit(user, "emergency stop" if spec is None else f"emergency stop of arena {spec.name}",
                                None if not active else active[0], tx=tx)
        for name, control in self._named_controls():
            if spec is None or name == spec.name:
                control.emergency_stop()
        self.notify()
        return self.arena_state(user)

    def release_arena(self, user: User, arena: str | None = None) -> ArenaState:
        """Release the emergency stop (of every arena, or of ``arena``): the arena takes the next waiting job."""
        self._require_operator(user)
        spec = None if arena is None else self._spec(arena)
        with self.store.transaction() as tx:
            if spec is None:
                if not self.store.arena_stopped():
                    raise Conflict("the arena is not stopped", "arena")
                self.store.set_arena_stopped(tx, False, attention="")
            else:
                if not self.store.arena_stopped_named(spec.name):
                    raise Conflict(f"arena {spec.name} is not stopped", "arena")
                self.store.set_arena_stopped_named(tx, spec.name, False)
            self.accounts.audit(user, "release emergency stop" + ("" if spec is None else f" of arena {spec.name}"),
                                tx=tx)
        self.notify()
        return self.arena_state(user)

    def emergency_stop_region(self, user: User, arena: str, region: str) -> dict[str, Any]:
        """Stop region ``region`` of ``arena`` (a floor divided into regions) now: its robots stop (the floor's one
        barrier keeps the other regions' robots running), its job ends (``cancelled``), and the region is latched
        stopped — its robots stay where they stopped and it takes no job — until :meth:`release_region`. Operators
        only; audited. The region's state (:meth:`regions_state`)."""
        self._require_operator(user)
        spec, placed = self._region(arena, region)
        with self.store.transaction() as tx:
            self.store.set_arena_stopped_named(tx, placed, True)
            active = [j.id for j in self.store.active_on(spec.name, self._default, tx) if j.placed == placed]
            for job_id in active:
                self.store.transition(tx, job_id, JobState.CANCELLED, ended=time.time(),
                                      reason=f"emergency stop of region {region} by operator {user.name}")
                self._event(tx, job_id, "ended")
            self.accounts.audit(user, f"emergency stop of region {placed}", None if not active else active[0], tx=tx)
        control = dict(self._named_controls()).get(spec.name)
        estop_region = getattr(control, "estop_region", None)
        if estop_region is not None:
            estop_region(region)
        self.notify()
        return self.regions_state(spec.name)

    def release_region(self, user: User, arena: str, region: str) -> dict[str, Any]:
        """Release region ``region``'s emergency stop: its robots return to their parking places and it takes the
        next job. Operators only; audited; :class:`~.errors.Conflict` when it is not stopped."""
        self._require_operator(user)
        spec, placed = self._region(arena, region)
        with self.store.transaction() as tx:
            if not self.store.arena_stopped_named(placed):
                raise Conflict(f"region {placed} is not stopped", "region")
            self.store.set_arena_stopped_named(tx, placed, False)
            self.accounts.audit(user, f"release emergency stop of region {placed}", tx=tx)
        self.notify()
        return self.regions_state(spec.name)

    def regions_state(self, arena: str) -> dict[str, Any]:
        """``{"arena", "regions": [{"name", "robots", "stopped", "job"}]}`` of a floor divided into regions."""
        spec = self._spec(arena)
        on = {j.placed: j.id for j in self.store.active_on(spec.name, self._default)}
        return {"arena": spec.name, "regions": [
            {"name": r, "robots": spec.slot_capacity(k), "stopped": self.store.arena_stopped_named(spec.placed_name(k)),
             "job": on.get(spec.placed_name(k))} for k, r in enumerate(spec.slot_names)]}

    def _region(self, arena: str, region: str) -> tuple[ArenaSpec, str]:
        """The arena's spec and ``ARENA/REGION``; NotFound naming the arena's regions."""
        spec = self._spec(arena)
        if region not in spec.slot_names:
            known = ", ".join(spec.slot_names) or "none: its floor is not divided"
            raise NotFound(f"arena {spec.name} has no region {region!r} (regions: {known})", "region")
        return spec, spec.placed_name(spec.slot_names.index(region))

    def arena_state(self, user: User) -> ArenaState:
        """The arena, its queue, its alerts and its fleet as operators see it (:class:`ArenaState`)."""
        self._require_operator(user)
        first = self.arena if self.arena is not None else next(iter(self.runners.values()), None)
        arena = first if isinstance(first, ArenaReports) else None
        return ArenaState(stopped=self.arena_stopped, needs_operator=self.store.attention(),
                          alerts=None if arena is None else arena.alerts(), manual_approval=self.manual_approval,
                          running=self.store.on_arena(), queue=tuple(self.with_eta(self.store.queue())),
                          fleet=None if arena is None else arena.fleet_status(), arenas=tuple(self.arenas_state()))

    def audit_log(self, user: User, limit: int = 200) -> list[dict[str, Any]]:
        self._require_operator(user)
        return self.accounts.audit_log(limit)

    # ------------------------------------------------------------------ workers and runner
    def claim_for_verification(self) -> Job | None:
        """The next queued job, now ``verifying`` (None when there is none): round-robin over the owners
        of queued jobs — the next owner (by user id) after the one served last, wrapping around — and that
        owner's oldest queued job, so one researcher's many jobs never make another's wait behind them all.
        The owner served last is kept in the database (``settings``), so the turn survives a restart."""
        with self.store.transaction() as tx:
            found = self.store.next_for_verification(tx, self.store.last_verified_owner())
            if found is None:
                return None
            job_id, owner = found
            self.store.transition(tx, job_id, JobState.VERIFYING, sources=(JobState.AWAITING_VERIFICATION,))
            self.store.set_last_verified_owner(tx, owner)
        self.notify()
        return self.store.get(job_id)

    def finish_verification(self, job_id: int, verdict: str, safety_score: float | None,
                            reasons: list[str]) -> None:
        """Record the verdict: ``rejected``, or ``awaiting approval`` (then ``in arena queue`` unless manual
        approval is on or the job waits for a decision on its bypass). A job cancelled meanwhile stays cancelled."""
        accepted = verdict != REJECTED_VERDICT
        with self.store.transaction() as tx:
            try:
                self.store.transition(tx, job_id, JobState.AWAITING_APPROVAL if accepted else JobState.REJECTED,
                                      sources=(JobState.VERIFYING,),
                                      # S of a rejected script says nothing (it may never have moved a robot)
                                      verdict=verdict, safety_score=safety_score if accepted else None,
                                      reason=None if accepted else "; ".join(reasons)[:4000],
                                      ended=None if accepted else time.time())
            except TransitionConflict:
                return
            if accepted and self.store.bypass_pending(tx, job_id):  # a verdict alone never removes protection
                self.store.set_reason(tx, job_id, BYPASS_WAIT)
            elif accepted and not self.store.manual_approval():
                self.store.transition(tx, job_id, JobState.IN_ARENA_QUEUE, sources=(JobState.AWAITING_APPROVAL,))
            self._event(tx, job_id, "verified" if accepted else "rejected")
        self.notify()

    def fail_verification(self, job_id: int, reason: str) -> None:
        """Verification could not run (infrastructure): the job is ``rejected`` with the reason."""
        self.finish_verification(job_id, REJECTED_VERDICT, None, [f"verification could not run: {reason}"])

    def verifying_cancelled(self, job_id: int) -> bool:
        return self.store.state(job_id) != JobState.VERIFYING

    @staticmethod
    def bypass_allowed(job: Job | Mapping[str, Any]) -> bool:
        """Run ``job`` (a :class:`.Job`, or its JSON from the API) without the barrier, with the guard:
        :attr:`.Job.bypass_allowed`."""
        if isinstance(job, Job):
            return job.bypass_allowed
        return bypass_decided(job.get("verdict"), bool(job.get("request_no_barrier")),
                              bool(job.get("barrier_forbidden")), job.get("bypass_decision"), BypassDecision.APPROVED)

    def claim_for_arena(self, admit: Callable[[Job], str | None] | None = None, arena: str | None = None,
                        holder: str | None = None, only: int | None = None, slot: int | None = None) -> Job | None:
        """The first job of the arena queue the plan puts on ``arena`` now (:meth:`next_for`; None: the portal's
        first arena), now ``setting up`` on it — None when there is none or the arena is stopped. Of several
        arenas claiming at once each job goes to exactly one (the conditional transition).

        ``admit(job)`` (the arena: are N charged robots free?) returns None to go ahead, or why the job
        must wait: it stays first in the queue with that ``reason`` (jobs run in queue order:
        a smaller job behind it does not overtake it). ``admit`` runs outside the database transaction.
        ``holder``: the remote runner's lease that will hold the job; ``only``: claim that job or none (the
        remote runner checked its robots for it; :mod:`.remote`). ``slot``: the region of a divided floor that claims
        (:mod:`.region_runner`): the first job the plan starts on that region now; ``placed`` records ``ARENA/REGION``.
        """
        name = self._default if arena is None else arena
        spec = self._spec(name) if slot is not None else None
        admitted = None
        if admit is not None:
            if self.stopped_here(name, slot):
                return None
            first = self.next_for(name, slot=slot)
            if first is None:
                return None
            why = admit(first)
            if why is not None:
                if self.store.set_waiting_reason(first.id, why[:4000]):
                    self.notify()
                return None
            admitted = first.id
        with self.store.transaction() as tx:
            if self.stopped_here(name, slot):
                return None
            job = self.next_for(name, slot=slot)  # this thread's connection is tx's: the plan reads what tx sees
            if job is None or (admit is not None and job.id != admitted) or (only is not None and job.id != only):
                return None  # the queue changed meanwhile: the arena asks again
            self.store.transition(tx, job.id, JobState.SETTING_UP, sources=(JobState.IN_ARENA_QUEUE,),
                                  started=time.time(), bypass=int(job.bypass_allowed), reason=None,
                                  placed=name if spec is None else spec.placed_name(slot), holder=holder)
        self.notify()
        return self.store.get(job.id)

    def arena_needs_operator(self, message: str) -> None:
        """The arena cannot look after itself (a return to the chargers failed): it stops (no job starts,
        as after an emergency stop) and ``message`` (the robots named) is shown to operators until one
        releases it (:meth:`release_arena`)."""
        with self.store.transaction() as tx:
            self.store.set_arena_stopped(tx, True, attention=message[:4000])
        self.notify()

    def mark_running(self, job_id: int) -> bool:
        """``setting up → running``; False if the job was cancelled (or e-stopped) meanwhile."""
        with self.store.transaction() as tx:
            try:
                self.store.transition(tx, job_id, JobState.RUNNING, sources=(JobState.SETTING_UP,))
            except TransitionConflict:
                return False
            self._event(tx, job_id, "started")
        self.notify()
        return True

    def finish_run(self, job_id: int, state: JobState, reason: str | None) -> JobState | None:
        """End a run (``done``/``failed``/``cancelled``) unless it already ended (cancelled, e-stopped):
        the job's final state (None: there is no such job)."""
        with self.store.transaction() as tx:
            try:
                self.store.transition(tx, job_id, state, sources=ACTIVE, ended=time.time(), reason=reason)
            except TransitionConflict as exc:
                return None if exc.state is None else JobState(exc.state)
            self._event(tx, job_id, "ended")
        self.notify()
        return JobState(state)

    def set_exports(self, job_id: int, state: ExportState) -> None:
        """Where the job's exports are (:class:`.ExportState`; :mod:`.exports`)."""
        self.store.set_exports(job_id, state)
        self.notify()

    def exports_in(self, state: ExportState) -> list[int]:
        """The ids of the jobs whose exports are in ``state``, oldest first."""
        return self.store.exports_in(state)

    def job_state(self, job_id: int) -> JobState | None:
        return self.store.state(job_id)

    def recover_on_start(self) -> list[int]:
        """After a restart: jobs found on the arena become ``interrupted`` (their ids are returned, for the
        runner to recover their recordings); jobs found ``verifying`` go back to ``awaiting verification``."""
        with self.store.transaction() as tx:
            ids = self.store.ids_in(tx, ACTIVE)
            ids = [i for i in ids if self.store.holder_of(i) is None]  # remote runners' jobs: their leases decide
            for jid in ids:
                self.store.transition(tx, jid, JobState.INTERRUPTED, sources=ACTIVE, ended=time.time(),
                                      reason="the server stopped during the run (partial recording kept)")
                self._event(tx, jid, "ended")
            for jid in self.store.ids_in(tx, (JobState.VERIFYING,)):
                self.store.transition(tx, jid, JobState.AWAITING_VERIFICATION, sources=(JobState.VERIFYING,))
        return ids

    def close(self) -> None:
        self.db.close()

    # ------------------------------------------------------------------ several arenas (issue 30)
    @property
    def _default(self) -> str:
        return self.config.arena_specs()[0].name

    def _spec(self, name: str) -> ArenaSpec:
        for spec in self.config.arena_specs():
            if spec.name == name:
                return spec
        raise NotFound(f"there is no arena {name!r} (arenas: "
                       f"{', '.join(a.name for a in self.config.arena_specs())})", "arena")

    def _named_controls(self) -> list[tuple[str, ArenaControl]]:
        named = list(self.runners.items())
        if self.arena is not None and all(c is not self.arena for _, c in named):
            named.append((self._default, self.arena))
        return named

    def _controls(self) -> list[ArenaControl]:
        return [c for _, c in self._named_controls()]

    def _user_named(self, name: str) -> User | None:
        try:
            return self.accounts.user_named(name)
        except NotFound:
            return None

    def _stopped(self, arena: str) -> bool:
        """Whether ``arena`` may not start a job: the portal's latch or its own."""
        return self.store.arena_stopped() or self.store.arena_stopped_named(arena)

    def connected(self, arena: str, now: float | None = None) -> bool:
        """Whether ``arena`` can take jobs now: in-process, or its remote runner was heard from within the
        lease time (:attr:`PortalConfig.runner_lease_s`)."""
        spec = self._spec(arena)
        if not spec.remote:
            return True
        lease = self.lab.lease(arena)
        now = time.time() if now is None else now
        return lease is not None and now - lease[1] <= self.config.runner_lease_s

    def _windows(self, now: float) -> list[Window]:
        out = []
        for r in self.lab.reservations(now):
            users = {r.user_id} if r.user_id is not None else set(self.lab.members(r.group or ""))
            out.append(Window(r.arena, r.start, r.end, frozenset(users)))
        return out

    def plan(self, jobs: list[Job], now: float) -> dict[int, Placement]:
        """Where and when each of ``jobs`` (in queue order) is planned (:func:`.scheduler.plan`) over the arenas
        that can take jobs now (not stopped; remote ones connected), their running jobs and the reservations."""
        default = self._default
        lanes: list[Lane] = []
        overheads: dict[str, float] = {}
        for spec in self.config.arena_specs():
            if self._stopped(spec.name) or not self.connected(spec.name, now):
                continue
            est = overheads[spec.name] = overhead(self.store.recent_runs(spec.name, default, OVERHEAD_RUNS))
            busy: list[list[tuple[float, float]]] = [[] for _ in range(spec.slots)]
            for k, j in enumerate(self.store.active_on(spec.name, default)):
                t0 = j.started if j.started is not None else now
                on = spec.slot_of(j.placed)  # a region's job: its region's lane (and the regions nested with it)
                slot = k % spec.slots if on is None else on
                for taken in (slot, *spec.conflicts(slot)):
                    busy[taken].append((t0, t0 + occupancy(j.duration, est)))
            lanes += [Lane(spec.name, k, spec.kind, spec.slot_capacity(k), busy[k], spec.slot_shape(k),
                           spec.conflicts(k))
                      for k in range(spec.slots)
                      if not (spec.slot_names and any(self.store.arena_stopped_named(spec.placed_name(s))
                                                      for s in (k, *spec.conflicts(k))))]
        pending = [Pending(j.id, j.user_id, j.robots, j.duration, j.arena, j.needs, self.job_bounds(j))
                   for j in jobs]
        return plan(pending, lanes, self._windows(now), now, overheads)

    def job_bounds(self, job: Job) -> Bounds:
        """The arena ``job``'s script will see, m — what verification checks it against
        (:meth:`.workers.VerificationWorkers.config_for`) and the only lanes the plan puts it on: on the first
        arena that fits it, the region it gets there (:meth:`.arenas.ArenaSpec.job_bounds`: on a floor divided into
        regions, the smallest region that holds its robots), else the whole floor."""
        for spec in self.config.arena_specs():
            if spec.fits(job.robots, job.needs, job.arena):
                return spec.job_bounds(job.robots)
        return DEFAULT_BOUNDS

    def next_for(self, arena: str, now: float | None = None, slot: int | None = None) -> Job | None:
        """The first job of the arena queue the plan starts on ``arena`` (on its ``slot``: None, any) now (None:
        none)."""
        now = time.time() if now is None else now
        queue = self.store.queue()
        placements = self.plan(queue, now)
        for job in queue:
            p = placements.get(job.id)
            if p is not None and p.arena == arena and (slot is None or p.slot == slot) and p.start <= now:
                return job
        return None

    def stopped_here(self, arena: str | None, slot: int | None = None) -> bool:
        """Whether ``arena`` (None: the portal's first) — or its region ``slot`` — may not start a job now: the
        portal's latch, the arena's, or the region's (:meth:`emergency_stop_region`)."""
        name = self._default if arena is None else arena
        if self._stopped(name):
            return True
        if slot is None:
            return False
        spec = self._spec(name)
        return bool(spec.slot_names) and self.store.arena_stopped_named(spec.placed_name(slot))

    def with_eta(self, jobs: list[Job]) -> list[Job]:
        """``jobs`` with the estimated start, end and arena of those waiting (the arena queue, verification and
        approval: :meth:`plan` over every waiting job, the queue first)."""
        planned = (JobState.IN_ARENA_QUEUE, *PRE_QUEUE)
        if not any(j.state in planned for j in jobs):
            return jobs
        placements = self.plan(self.store.waiting_in_order(), time.time())
        out = []
        for j in jobs:
            p = placements.get(j.id) if j.state in planned else None
            out.append(j if p is None else replace(j, eta_start=p.start, eta_end=p.end, eta_arena=p.arena))
        return out

    def arenas_state(self) -> list[dict[str, Any]]:
        """Each arena: its spec, whether it is stopped and connected, and the jobs on it now."""
        controls = dict(self._named_controls())
        out = []
        for spec in self.config.arena_specs():
            on = self.store.active_on(spec.name, self._default)
            control = controls.get(spec.name)
            fleet = control.fleet_status() if isinstance(control, ArenaReports) else None
            out.append({**spec.to_dict(), "stopped": self._stopped(spec.name), "connected": self.connected(spec.name),
                        "running": [j.id for j in on], "fleet": fleet,
                        "regions": self.regions_state(spec.name)["regions"] if spec.slot_names else None})
        return out

    # ------------------------------------------------------------------ reservations
    def reservations(self, user: User) -> list[Reservation]:
        """The reservations that have not ended (everyone sees them: the queue plans around them)."""
        return self.lab.reservations(time.time())

    def reserve(self, user: User, *, arena: Any, start: Any, end: Any, for_user: Any = None, group: Any = None,
                note: Any = "") -> Reservation:
        """An operator books ``arena`` over [start, end) (UNIX s) for a researcher (``for_user``, a name) or a
        ``group``: only their jobs run there then, and the queue plans around it. 409 when it overlaps another
        reservation of that arena; 400 when it lies in the past, ends before it starts, names no one or an
        unknown arena or user."""
        self._require_operator(user)
        if not isinstance(arena, str):
            raise BadInput("arena must be an arena's name", "arena")
        spec = self._spec(arena)
        for key, v in (("start", start), ("end", end)):
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise BadInput(f"{key} must be a time in UNIX seconds, got {v!r}", key)
        start, end = float(start), float(end)
        now = time.time()
        if end <= start:
            raise BadInput(f"the reservation ends ({end:.0f}) before it starts ({start:.0f})", "end")
        if end <= now:
            raise BadInput("the reservation lies in the past (it ends before now)", "end")
        if (for_user is None) == (group is None):
            raise BadInput("name either a researcher (user) or a group the reservation is for", "user")
        user_id = None
        if for_user is not None:
            target = self._user_named(for_user) if isinstance(for_user, str) else None
            if target is None:
                raise BadInput(f"there is no user {for_user!r}", "user")
            user_id = target.id
        elif not isinstance(group, str) or not group.strip() or len(group) > 64:
            raise BadInput(f"group must be a group's name, got {group!r}", "group")
        if not isinstance(note, str) or len(note) > 200:
            raise BadInput("note must be a text of at most 200 characters", "note")
        with self.store.transaction() as tx:
            clash = self.lab.overlapping(tx, spec.name, max(start, now), end)
            if clash is not None:
                raise Conflict(f"arena {spec.name} is already reserved from {_clock(clash.start)} to "
                               f"{_clock(clash.end)} UTC for {clash.user or 'group ' + str(clash.group)} "
                               f"(reservation {clash.id})", "start")
            res_id = self.lab.add_reservation(tx, arena=spec.name, user_id=user_id, group=group, start=start,
                                              end=end, note=note, created_by=user.id)
            self.accounts.audit(user, "reserve", None, f"arena {spec.name} {_clock(start)}–{_clock(end)} for "
                                f"{for_user if for_user is not None else 'group ' + str(group)}", tx=tx)
        self.notify()
        found = self.lab.reservation(res_id)
        assert found is not None
        return found

    def cancel_reservation(self, user: User, res_id: int) -> None:
        self._require_operator(user)
        with self.store.transaction() as tx:
            if not self.lab.delete_reservation(tx, res_id):
                raise NotFound(f"no reservation {res_id}", "reservation")
            self.accounts.audit(user, "cancel reservation", None, str(res_id), tx=tx)
        self.notify()

    def set_group(self, user: User, name: str, group: str | None) -> dict[str, Any]:
        """An operator puts researcher ``name`` in ``group`` (None: none): reservations for a group cover them."""
        self._require_operator(user)
        target = self._user_named(name)
        if target is None:
            raise NotFound(f"no user {name!r}", "user")
        if group is not None and (not isinstance(group, str) or not group.strip() or len(group) > 64):
            raise BadInput(f"group must be a name of at most 64 characters, got {group!r}", "group")
        with self.store.transaction() as tx:
            self.lab.set_group(tx, target.id, group)
            self.accounts.audit(user, "set group", None, f"{name}: {group}", tx=tx)
        self.notify()
        return {"user": name, "group": group}

    # ------------------------------------------------------------------ notifications
    def notification_targets(self, user: User) -> dict[str, Any]:
        webhook, email = self.lab.targets(user.id)
        return {"webhook": webhook, "email": email, "email_configured": self.config.smtp is not None,
                "sent": self.lab.notices(user.id, 20)}

    def set_notification_targets(self, user: User, webhook: Any, email: Any) -> dict[str, Any]:
        """Where ``user`` is told when their jobs are verified, start, end or are rejected (None: nowhere)."""
        webhook = None if webhook in (None, "") else check_webhook(webhook)
        email = None if email in (None, "") else check_email(email)
        self.lab.set_targets(user.id, webhook, email)
        return self.notification_targets(user)

    def _event(self, tx: Any, job_id: int, event: str) -> None:
        """Queue the owner's notifications of ``event`` (verified, rejected, started, ended) in ``tx``: sent by
        :class:`.notify.Notifier` off the queue's path, with the change they report committed."""
        job = self.store.get(job_id, tx)
        if job is None:
            return
        webhook, email = self.lab.targets(job.user_id, tx)
        if webhook is None and (email is None or self.config.smtp is None):
            return
        now = time.time()
        body = json.dumps({"event": event, "job": job.id, "name": job.name, "owner": job.owner, "state": job.state,
                           "reason": job.reason, "arena": job.placed, "time": now})
        if webhook is not None:
            self.lab.enqueue(tx, job_id=job.id, user_id=job.user_id, event=event, channel="webhook", target=webhook,
                             body=body, now=now)
        if email is not None and self.config.smtp is not None:
            self.lab.enqueue(tx, job_id=job.id, user_id=job.user_id, event=event, channel="email", target=email,
                             body=body, now=now)


def _clock(t: float) -> str:
    return time.strftime("%Y-%m-%d %H:%M", time.gmtime(t))
