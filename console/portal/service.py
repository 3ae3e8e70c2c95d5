"""The portal's rules, in one place: submissions, who sees what, the queue, operator actions, the arena's latch.

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
* **Ids** from outside are checked (:func:`valid_id`): one SQLite cannot hold is "no job" (404), never a 500.

Result files (:meth:`PortalService.files`): a fixed list of names
(:data:`RESULT_FILES`) under the job's folder; a download names one of them,
never a path.
"""
from __future__ import annotations

import json
import math
import shutil
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from swarmdeck.console.jobs.bundle import ScriptBundle
from swarmdeck.console.jobs.confinement import JailConfig, SandboxLimits
from swarmdeck.console.jobs.script_env import ScriptEnv, listing
from swarmdeck.console.portal.accounts import Accounts, User
from swarmdeck.console.portal.db import ACTIVE, FINAL, Database, TransitionConflict
from swarmdeck.console.portal.errors import BadInput, Conflict, Forbidden, NotFound, Unavailable
from swarmdeck.console.portal.exports import EXPORT_FILES
from swarmdeck.console.portal.files import private_dir, write_private
from swarmdeck.console.portal.quotas import Quotas, check_counts, check_disk
from swarmdeck.console.portal.quotas import usage as quota_usage
from swarmdeck.console.portal.results import results_summary
from swarmdeck.console.portal.states import JobState
from swarmdeck.console.portal.submission import Limits, Manifest, Upload, check_bundle, check_upload, parse_manifest

#: result files a job may have, name -> what it is (the exports, :mod:`.exports`, write four of them after the run).
RESULT_FILES: dict[str, str] = {
    "recording.mcap": "the run's MCAP recording (swarmdeck play / Foxglove)",
    "recording.partial.mcap": "the recording as the interrupted run left it (before recovery)",
    "robots.csv": "poses and commands per robot per frame (CSV)",
    "frames.csv": "one row per frame (CSV)",
    "replay.html": "standalone 3D replay (open in a browser)",
    "video.mp4": "top-down video of the run",
    "script.log": "the script's output (stdout and stderr)",
    "report.json": "the verification report (JSON)",
    "report.html": "the verification report (HTML)",
    "run.json": "how the run ended (JSON)",
    "manifest.json": "the manifest as accepted",
}
BYPASS_VERDICT = "accepted, may bypass the barrier"
BYPASS_WAIT = "waiting for an operator to approve running without the barrier"
#: SQL: the job waits for an operator's decision on its bypass (columns of ``jobs``)
_PENDING_SQL = ("(COALESCE(verdict, '') = 'accepted, may bypass the barrier' AND request_no_barrier = 1 "
                "AND barrier_forbidden = 0 AND bypass_decision IS NULL)")


class ArenaControl(Protocol):
    """What the service asks of the arena runner (:class:`~.runner.ArenaRunner`)."""

    def emergency_stop(self) -> None: ...

    def cancel(self, job_id: int) -> None: ...


@dataclass(frozen=True)
class PortalConfig:
    """The service's settings.

    Attributes:
        data: the data folder (database, ``jobs/<id>/``).
        limits: what a submission may be (fleet size, maximum duration, upload sizes).
        verify_runs: verification runs per job (each without and with the barrier).
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
            (:mod:`swarmdeck.console.jobs.script_env`); None: what swarmdeck's own environment has.
        retain_days: results of jobs that ended more than this many days ago are deleted by
            :meth:`PortalService.sweep_results` (the job's row stays, with ``results_deleted``); None: kept.
    """

    data: Path
    limits: Limits = field(default_factory=Limits)
    verify_runs: int = 4
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


def _job_dict(row: Any, position: int | None = None) -> dict[str, Any]:
    poses = row["initial_poses"]
    return {
        "id": row["id"], "name": row["name"], "owner": row["owner"], "state": row["state"],
        "held_from": row["held_from"], "kind": row["kind"], "script": row["script_name"], "entry": row["entry"],
        "robots": row["n_robots"], "duration": row["duration"],
        "initial_poses": None if poses is None else json.loads(poses),
        "request_no_barrier": bool(row["request_no_barrier"]), "barrier_forbidden": bool(row["barrier_forbidden"]),
        "verdict": row["verdict"], "safety_score": row["safety_score"],
        "bypass": None if row["bypass"] is None else bool(row["bypass"]), "reason": row["reason"],
        "bypass_decision": row["bypass_decision"], "bypass_pending": _bypass_pending(row),
        "position": position, "created": row["created"], "updated": row["updated"], "started": row["started"],
        "ended": row["ended"], "exports": row["exports"], "results_deleted": row["results_deleted"],
    }


def _bypass_pending(row: Any) -> bool:
    """The job asks to run without the barrier, verification allowed it, and no operator decided yet."""
    return (row["verdict"] == BYPASS_VERDICT and bool(row["request_no_barrier"]) and not row["barrier_forbidden"]
            and row["bypass_decision"] is None)


def valid_id(job_id: Any) -> bool:
    """Whether ``job_id`` can be a job's id: an integer, 1 <= id < 2**63 (what SQLite's INTEGER holds)."""
    return isinstance(job_id, int) and not isinstance(job_id, bool) and 1 <= job_id < 2 ** 63


JOB_SELECT = "SELECT j.*, u.name AS owner FROM jobs j JOIN users u ON u.id = j.user_id"


class PortalService:
    """The rules (module docstring) over the :class:`Database` and :class:`Accounts`."""

    def __init__(self, config: PortalConfig, *, db: Database | None = None, accounts: Accounts | None = None) -> None:
        self.config = config
        self.data = Path(config.data)
        self.db = db if db is not None else Database(self.data)
        self.accounts = accounts if accounts is not None else Accounts(self.db)
        private_dir(self.data / "jobs")  # the data folder itself is made 0700 by the Database
        self.changed = threading.Condition()  # notified after every change workers/runner/live views wait on
        self.arena: ArenaControl | None = None
        self._video_lock = threading.Lock()  # videos are made one at a time (video())

    # ------------------------------------------------------------------ helpers
    def job_dir(self, job_id: int) -> Path:
        return self.data / "jobs" / str(int(job_id))

    def notify(self) -> None:
        with self.changed:
            self.changed.notify_all()

    def wait_for_change(self, timeout: float) -> None:
        """Block until something changed (or ``timeout`` s passed; other processes' changes are seen by polling)."""
        with self.changed:
            self.changed.wait(timeout)

    def _row(self, job_id: int) -> Any:
        if not valid_id(job_id):
            return None  # an id SQLite cannot hold (>= 2**63) or < 1 is no job: 404 like any other
        return self.db.query_one(f"{JOB_SELECT} WHERE j.id = ?", (int(job_id),))

    def _visible_row(self, user: User, job_id: int) -> Any:
        row = self._row(job_id)
        if row is None or (not user.is_operator and row["user_id"] != user.id):
            raise NotFound(f"no job {job_id}", "job")
        return row

    def _queue_positions(self) -> dict[int, int]:
        rows = self.db.query(f"SELECT id FROM jobs WHERE state = '{JobState.IN_ARENA_QUEUE}' ORDER BY priority, id")
        return {int(r["id"]): k for k, r in enumerate(rows)}

    @staticmethod
    def _require_operator(user: User) -> None:
        if not user.is_operator:
            raise Forbidden("this needs an operator account", "Authorization")

    # ------------------------------------------------------------------ researchers
    def submit(self, user: User, filename: str | None, data: bytes, manifest: Any = None,
               entry: str | None = None) -> dict[str, Any]:
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
        entry = self._entry(m, upload)
        if not user.is_operator:
            check_disk(self.db.query("SELECT id FROM jobs WHERE user_id = ? AND results_deleted IS NULL",
                                     (user.id,)), self.config.quotas, self.data / "jobs")
        now = time.time()
        with self.db.transaction() as tx:
            if not user.is_operator:
                check_counts(tx, self.config.quotas, user.id, now)
            top = tx.execute("SELECT COALESCE(MAX(priority), 0) FROM jobs").fetchone()[0]
            job_id = tx.execute(
                "INSERT INTO jobs (user_id, name, state, kind, script_name, entry, n_robots, duration, initial_poses, "
                f"request_no_barrier, priority, created, updated) VALUES (?, ?, '{JobState.AWAITING_VERIFICATION}', ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (user.id, m.name, upload.kind, upload.display_name, entry, m.robots, m.duration,
                 None if m.initial_poses is None else json.dumps(m.initial_poses), int(m.no_barrier), top + 1,
                 now, now)).lastrowid
            self._store(int(job_id), upload, m, entry)  # inside the transaction: no job row without its files
        self.notify()
        return self.job(user, int(job_id))

    @staticmethod
    def _entry(m: Manifest, upload: Upload) -> str:
        if upload.kind == "py":
            return "script.py"
        entry = m.entry or upload.entry
        check_bundle(upload.files, entry)
        return str(entry)

    def _store(self, job_id: int, upload: Upload, m: Manifest, entry: str) -> None:
        folder = self.job_dir(job_id)
        if folder.exists():  # a leftover of a transaction that rolled back
            shutil.rmtree(folder)
        private_dir(folder)
        if upload.kind == "py":
            write_private(folder / "script.py", upload.files["script.py"])
        else:
            ScriptBundle.from_files(upload.files, entry).write_to(private_dir(folder / "src"), file_mode=0o600,
                                                                  dir_mode=0o700)
        write_private(folder / "manifest.json", json.dumps(m.to_dict(), indent=2))

    def script(self, job: dict[str, Any]) -> tuple[Path, str | None]:
        """What the sandbox runs for ``job``: ``(script.py, None)``, or ``(the archive's folder, its entry)``."""
        folder = self.job_dir(job["id"])
        return (folder / "script.py", None) if job["kind"] == "py" else (folder / "src", job["entry"])

    def jobs(self, user: User, *, mine: bool = False) -> list[dict[str, Any]]:
        """A researcher's own jobs; an operator's view of all jobs (``mine``: only their own). Newest first."""
        positions = self._queue_positions()
        if user.is_operator and not mine:
            rows = self.db.query(f"{JOB_SELECT} ORDER BY j.id DESC")
        else:
            rows = self.db.query(f"{JOB_SELECT} WHERE j.user_id = ? ORDER BY j.id DESC", (user.id,))
        return [_job_dict(r, positions.get(int(r["id"]))) for r in rows]

    def job(self, user: User, job_id: int) -> dict[str, Any]:
        row = self._visible_row(user, job_id)
        return _job_dict(row, self._queue_positions().get(int(row["id"])))

    def cancel(self, user: User, job_id: int) -> dict[str, Any]:
        """Cancel a job that has not ended (its owner, or an operator); 409 if it has ended."""
        row = self._visible_row(user, job_id)
        with self.db.transaction() as tx:
            try:
                self.db.transition(tx, int(job_id), JobState.CANCELLED, ended=time.time(),
                                   reason=f"cancelled by {user.name}")
            except TransitionConflict as exc:
                if exc.state in FINAL:
                    raise Conflict(f"job {job_id} has already ended ({exc.state}): there is nothing to cancel",
                                   "job") from None
                raise Conflict(str(exc), "job") from None
            if user.is_operator and row["user_id"] != user.id:
                self.accounts.audit(user, "cancel", int(job_id), tx=tx)
        if row["state"] in ACTIVE and self.arena is not None:
            self.arena.cancel(int(job_id))
        self.notify()
        return self.job(user, job_id)

    def report(self, user: User, job_id: int) -> dict[str, Any]:
        """The verification report (JSON) of a job; 404 until verification has finished."""
        self._require_results(self._visible_row(user, job_id))
        path = self.job_dir(job_id) / "report.json"
        if not path.is_file():
            raise NotFound(f"job {job_id} has no verification report yet", "job")
        return json.loads(path.read_text())

    def run_summary(self, user: User, job_id: int) -> dict[str, Any] | None:
        """How the arena run went (``run.json``: how it ended, the robots' set-up and return), None before
        it ended (or when the file cannot be read)."""
        self._visible_row(user, job_id)
        try:
            data = json.loads((self.job_dir(job_id) / "run.json").read_text())
        except (OSError, ValueError):
            return None
        return data if isinstance(data, dict) else None

    def results(self, user: User, job_id: int) -> dict[str, Any]:
        """The results summary of an ended job (:func:`.results.results_summary`); 404 while it has not ended."""
        row = self._visible_row(user, job_id)
        if row["state"] not in FINAL:
            raise NotFound(f"job {job_id} is {row['state']}: its results come when it has ended", "job")
        return results_summary(_job_dict(row), self.run_summary(user, job_id), self.files(user, job_id))

    def script_log(self, user: User, job_id: int, since: int = 0) -> dict[str, Any]:
        """The job's script output from byte ``since`` on: ``{"text", "next", "live"}`` — while it runs, what the
        script printed so far (the arena runner's live copy); after, ``script.log``. Its owner and operators."""
        row = self._visible_row(user, job_id)
        if isinstance(since, bool) or not isinstance(since, int) or since < 0:
            raise BadInput(f"since must be an integer >= 0, got {since!r}", "since")
        live = getattr(self.arena, "live_log", None)
        data = live(int(job_id)) if live is not None else None  # the runner's copy until script.log is written
        if data is None:
            self._require_results(row)
            try:
                data = (self.job_dir(job_id) / "script.log").read_bytes()
            except OSError:
                data = b""
        chunk = data[since:]
        return {"text": chunk.decode("utf-8", errors="replace"), "next": since + len(chunk),
                "live": row["state"] in ACTIVE}

    def files(self, user: User, job_id: int) -> list[dict[str, Any]]:
        """The job's result files that exist: ``{"name", "bytes", "what"}``."""
        self._visible_row(user, job_id)
        folder = self.job_dir(job_id)
        return [{"name": name, "bytes": (folder / name).stat().st_size, "what": what}
                for name, what in RESULT_FILES.items() if (folder / name).is_file()]

    def file_path(self, user: User, job_id: int, name: str) -> Path:
        """The path of result file ``name`` of the job (one of :data:`RESULT_FILES`); 404 otherwise.
        ``video.mp4`` is made from the recording on its first request (:meth:`video`)."""
        if name == "video.mp4":
            return self.video(user, job_id)
        row = self._visible_row(user, job_id)
        if name not in RESULT_FILES:
            raise NotFound(f"no result file called {name[:100]!r}", "name")
        self._require_results(row)
        path = self.job_dir(job_id) / name
        if not path.is_file():
            if row["exports"] == "writing" and name in EXPORT_FILES:
                raise Unavailable(f"job {job_id}'s exports are still being written: {name} is not ready yet", "name")
            raise NotFound(f"job {job_id} has no {name} (yet)", "name")
        return path

    def video(self, user: User, job_id: int) -> Path:
        """The job's ``video.mp4`` (top-down, H.264): written with the job's exports (:mod:`.exports`; 503
        while they are being written); if they did not write it, rendered from its recording on the first request
        (:func:`~swarmdeck.console.recording.export_video.export_video`, one at a time) and kept; 404 while
        the job is not over or has no recording, 503 when it cannot be made."""
        from swarmdeck.console.recording.export_video import VideoExportError, export_video
        from swarmdeck.console.recording.reader import RecordingError, open_recording

        row = self._visible_row(user, job_id)
        self._require_results(row)
        folder = self.job_dir(job_id)
        out, recording = folder / "video.mp4", folder / "recording.mcap"
        if out.is_file():
            return out
        if row["exports"] == "writing":
            raise Unavailable(f"job {job_id}'s exports are still being written: the video follows the CSV and "
                              "the replay", "name")
        if row["state"] not in FINAL or not recording.is_file():
            raise NotFound(f"job {job_id} has no video (yet): it is made from the recording once the run is over",
                           "name")
        with self._video_lock:
            if not out.is_file():
                try:
                    with open_recording(recording) as rec:
                        export_video(rec, out)
                except (RecordingError, VideoExportError, OSError) as exc:
                    raise Unavailable(f"the video of job {job_id} could not be made: {exc}", "name") from None
        return out

    def _require_results(self, row: Any) -> None:
        """NotFound when the retention sweep deleted the job's results (saying when and why)."""
        if row["results_deleted"] is not None:
            days = "" if self.config.retain_days is None else f" (the lab keeps results {self.config.retain_days:g} days)"
            raise NotFound(f"job {row['id']}'s results were deleted on "
                           f"{time.strftime('%Y-%m-%d', time.gmtime(row['results_deleted']))}{days}", "job")

    # ------------------------------------------------------------------ quotas and retention
    def record_verification_cpu(self, job_id: int, cpu_s: float) -> None:
        """Charge ``cpu_s`` CPU seconds of verification to the job's owner (the daily limit, :mod:`.quotas`)."""
        if not (isinstance(cpu_s, (int, float)) and math.isfinite(cpu_s) and cpu_s >= 0):
            return
        with self.db.transaction() as tx:
            tx.execute("INSERT OR REPLACE INTO verification_usage (job_id, user_id, t, cpu_s) "
                       "SELECT id, user_id, ?, ? FROM jobs WHERE id = ?", (time.time(), float(cpu_s), int(job_id)))

    def environment(self) -> dict[str, Any]:
        """What scripts can import here (:func:`swarmdeck.console.jobs.script_env.listing`), read now: packages
        the lab adds show at once. Unavailable when the configured environment no longer follows its rule."""
        try:
            env = None if self.config.script_env is None else ScriptEnv.open(self.config.script_env)
        except ValueError as exc:
            raise Unavailable(f"the lab's script environment is broken: {exc}") from None
        return listing(env)

    def usage(self, user: User) -> dict[str, Any]:
        """The researcher's use of each limit (:func:`.quotas.usage`; operators: limits None, not limited)."""
        marks = ", ".join("?" * len(FINAL))
        unfinished = self.db.query_one(f"SELECT COUNT(*) FROM jobs WHERE user_id = ? AND state NOT IN ({marks})",
                                       (user.id, *FINAL))[0]
        cpu = self.db.query("SELECT cpu_s FROM verification_usage WHERE user_id = ? AND t > ?",
                            (user.id, time.time() - 86400.0))
        rows = self.db.query("SELECT id FROM jobs WHERE user_id = ? AND results_deleted IS NULL", (user.id,))
        return quota_usage(unfinished, cpu, rows, Quotas(None, None, None) if user.is_operator else self.config.quotas,
                           self.data / "jobs")

    def sweep_results(self, now: float | None = None) -> list[int]:
        """Delete the folders (script, recording, exports, logs, reports) of jobs that ended more than
        ``retain_days`` ago and whose exports are not being written; each job's row stays, with
        ``results_deleted`` set (shown on its page). The ids swept (none when ``retain_days`` is None)."""
        if self.config.retain_days is None:
            return []
        now = time.time() if now is None else float(now)
        cutoff = now - float(self.config.retain_days) * 86400.0
        marks = ", ".join("?" * len(FINAL))
        rows = self.db.query(f"SELECT id FROM jobs WHERE state IN ({marks}) AND ended IS NOT NULL AND ended < ? "
                             "AND results_deleted IS NULL AND COALESCE(exports, '') != 'writing' ORDER BY id",
                             (*FINAL, cutoff))
        swept = []
        for r in rows:
            job_id = int(r["id"])
            shutil.rmtree(self.job_dir(job_id), ignore_errors=True)
            with self.db.transaction() as tx:
                tx.execute("UPDATE jobs SET results_deleted = ? WHERE id = ?", (now, job_id))
            swept.append(job_id)
        if swept:
            self.notify()
        return swept

    # ------------------------------------------------------------------ operators
    def _operator_transition(self, user: User, job_id: int, target: str, action: str,
                             sources: tuple[str, ...] | None = None, detail: str = "", **columns: Any) -> dict:
        self._require_operator(user)
        self._visible_row(user, job_id)
        with self.db.transaction() as tx:
            try:
                self.db.transition(tx, int(job_id), target, sources=sources, **columns)
            except TransitionConflict as exc:
                raise Conflict(str(exc), "job") from None
            self.accounts.audit(user, action, int(job_id), detail, tx=tx)
        self.notify()
        return self.job(user, job_id)

    def approve(self, user: User, job_id: int) -> dict[str, Any]:
        """Manual approval: ``approved → waiting``. A job waiting for a decision on its barrier bypass is
        refused (409): approve or refuse the bypass (:meth:`decide_bypass`)."""
        self._require_operator(user)
        if _bypass_pending(self._visible_row(user, job_id)):
            raise Conflict(f"job {job_id} asks to run without the barrier: approve or refuse that bypass "
                           f"(POST /api/operator/jobs/{job_id}/bypass {{\"approve\": true|false}})", "job")
        return self._operator_transition(user, job_id, JobState.IN_ARENA_QUEUE, "approve", sources=(JobState.AWAITING_APPROVAL,))

    def decide_bypass(self, user: User, job_id: int, approve: bool) -> dict[str, Any]:
        """An operator's decision on a job's barrier bypass (module docstring), audited with the verdict and S.

        Approve: the job goes ``waiting`` and runs without the barrier, with the guard (:mod:`swarmdeck.safety.guard`).
        Refuse: it runs with the barrier (``waiting``, or still ``approved`` while manual approval is on). 409 unless
        the job is ``approved`` and waiting for this decision."""
        self._require_operator(user)
        if not isinstance(approve, bool):
            raise BadInput(f"approve must be true or false, got {approve!r}", "approve")
        row = self._visible_row(user, job_id)
        if row["state"] != JobState.AWAITING_APPROVAL or not _bypass_pending(row):
            raise Conflict(f"job {job_id} is {row['state']} and not waiting for a decision on running without the "
                           "barrier", "job")
        score = "n/a" if row["safety_score"] is None else f"{row['safety_score']:.4f}"
        detail = f"verdict {row['verdict']!r}, S = {score}"
        target = JobState.IN_ARENA_QUEUE if approve or not self.manual_approval else JobState.AWAITING_APPROVAL
        columns = {"bypass_decision": "approved" if approve else "refused", "barrier_forbidden": int(not approve),
                   "reason": None}
        with self.db.transaction() as tx:
            if target == JobState.AWAITING_APPROVAL:  # manual approval on: the refused job now waits for the usual approval
                cur = tx.execute("UPDATE jobs SET bypass_decision = ?, barrier_forbidden = ?, reason = ?, updated = ? "
                                 f"WHERE id = ? AND state = '{JobState.AWAITING_APPROVAL}'", (*columns.values(), time.time(), job_id))
                if cur.rowcount != 1:
                    raise Conflict(f"job {job_id} is no longer awaiting approval", "job")
            else:
                try:
                    self.db.transition(tx, int(job_id), target, sources=(JobState.AWAITING_APPROVAL,), **columns)
                except TransitionConflict as exc:
                    raise Conflict(str(exc), "job") from None
            self.accounts.audit(user, "approve barrier bypass" if approve else "refuse barrier bypass", int(job_id),
                                detail, tx=tx)
        self.notify()
        return self.job(user, job_id)

    def hold(self, user: User, job_id: int) -> dict[str, Any]:
        """Hold a job awaiting verification or approval or in the arena queue (it keeps its place; :meth:`release` puts it back)."""
        self._require_operator(user)
        row = self._visible_row(user, job_id)
        return self._operator_transition(user, job_id, JobState.HELD, "hold", held_from=row["state"])

    def release(self, user: User, job_id: int) -> dict[str, Any]:
        """Release a held job to the state it was held in (an approved one to ``waiting`` if manual approval
        is off by now)."""
        self._require_operator(user)
        row = self._visible_row(user, job_id)
        if row["state"] != JobState.HELD:
            raise Conflict(f"job {job_id} is {row['state']}, not held", "job")
        back = row["held_from"] or JobState.AWAITING_VERIFICATION
        if back == JobState.AWAITING_APPROVAL and not self.manual_approval and not _bypass_pending(row):
            back = JobState.IN_ARENA_QUEUE  # manual approval was switched off while it was held
        return self._operator_transition(user, job_id, back, "release", sources=(JobState.HELD,), held_from=None)

    def operator_cancel(self, user: User, job_id: int) -> dict[str, Any]:
        self._require_operator(user)
        return self.cancel(user, job_id)

    def move(self, user: User, job_id: int, position: int) -> dict[str, Any]:
        """Put a waiting job at ``position`` (0: next) of the arena queue."""
        self._require_operator(user)
        self._visible_row(user, job_id)
        if isinstance(position, bool) or not isinstance(position, int) or position < 0:
            raise BadInput(f"position must be an integer >= 0, got {position!r}", "position")
        with self.db.transaction() as tx:
            ids = [int(r["id"]) for r in tx.execute(f"SELECT id FROM jobs WHERE state = '{JobState.IN_ARENA_QUEUE}' "
                                                    "ORDER BY priority, id").fetchall()]
            if int(job_id) not in ids:
                state = tx.execute("SELECT state FROM jobs WHERE id = ?", (job_id,)).fetchone()["state"]
                raise Conflict(f"job {job_id} is {state}: only jobs in the arena queue can be reordered", "job")
            ids.remove(int(job_id))
            ids.insert(min(position, len(ids)), int(job_id))
            base = tx.execute(f"SELECT COALESCE(MIN(priority), 0) FROM jobs WHERE state = '{JobState.IN_ARENA_QUEUE}'").fetchone()[0]
            for k, jid in enumerate(ids):
                tx.execute("UPDATE jobs SET priority = ? WHERE id = ?", (base + k * 1e-3, jid))
            # counted from 1, as the operator page and the CLI show positions (the API's ``position`` is 0-based)
            self.accounts.audit(user, "move", int(job_id), f"to position {min(position, len(ids) - 1) + 1}", tx=tx)
        self.notify()
        return self.job(user, job_id)

    def forbid_barrier(self, user: User, job_id: int, forbid: bool) -> dict[str, Any]:
        """Forbid (or allow again) running this job without the barrier; refused once it is on the arena."""
        self._require_operator(user)
        self._visible_row(user, job_id)
        if not isinstance(forbid, bool):
            raise BadInput(f"forbid must be true or false, got {forbid!r}", "forbid")
        with self.db.transaction() as tx:
            cur = tx.execute("UPDATE jobs SET barrier_forbidden = ?, updated = ? WHERE id = ? AND state NOT IN "
                             f"({', '.join('?' * len(ACTIVE + FINAL))})",
                             (int(forbid), time.time(), job_id, *ACTIVE, *FINAL))
            if cur.rowcount != 1:
                state = tx.execute("SELECT state FROM jobs WHERE id = ?", (job_id,)).fetchone()["state"]
                raise Conflict(f"job {job_id} is {state}: the barrier can no longer be changed", "job")
            self.accounts.audit(user, "forbid barrier bypass" if forbid else "allow barrier bypass", int(job_id), tx=tx)
            # a job waiting for the bypass decision that is now forbidden runs with the barrier; a waiting job whose
            # bypass is allowed again waits for an operator's decision on it
            if forbid and not self.manual_approval:
                tx.execute(f"UPDATE jobs SET state = '{JobState.IN_ARENA_QUEUE}', reason = NULL WHERE id = ? AND state = '{JobState.AWAITING_APPROVAL}' "
                           f"AND reason = ?", (job_id, BYPASS_WAIT))
            elif not forbid:
                tx.execute(f"UPDATE jobs SET state = '{JobState.AWAITING_APPROVAL}', reason = ? WHERE id = ? AND state = '{JobState.IN_ARENA_QUEUE}' "
                           f"AND {_PENDING_SQL}", (BYPASS_WAIT, job_id))
        self.notify()
        return self.job(user, job_id)

    @property
    def manual_approval(self) -> bool:
        return self.db.setting("manual_approval", "0") == "1"

    def set_manual_approval(self, user: User, on: bool) -> dict[str, Any]:
        """Switch manual approval; switching it off sends every approved job to the arena queue."""
        self._require_operator(user)
        if not isinstance(on, bool):
            raise BadInput(f"manual_approval must be true or false, got {on!r}", "manual_approval")
        with self.db.transaction() as tx:
            self.db.set_setting(tx, "manual_approval", "1" if on else "0")
            if not on:  # jobs waiting for a decision on their bypass keep waiting for it
                tx.execute(f"UPDATE jobs SET state = '{JobState.IN_ARENA_QUEUE}', updated = ? WHERE state = '{JobState.AWAITING_APPROVAL}' AND NOT {_PENDING_SQL}",
                           (time.time(),))
            self.accounts.audit(user, "manual approval on" if on else "manual approval off", tx=tx)
        self.notify()
        return self.settings()

    def settings(self) -> dict[str, Any]:
        return {"manual_approval": self.manual_approval}

    @property
    def arena_stopped(self) -> bool:
        return self.db.setting("arena_stopped", "0") == "1"

    def emergency_stop(self, user: User) -> dict[str, Any]:
        """Stop the robots now, end the running job, latch the arena stopped (see the module docstring)."""
        self._require_operator(user)
        with self.db.transaction() as tx:
            self.db.set_setting(tx, "arena_stopped", "1")
            active = tx.execute(f"SELECT id FROM jobs WHERE state IN ({', '.join('?' * len(ACTIVE))})",
                                ACTIVE).fetchall()
            for r in active:
                self.db.transition(tx, int(r["id"]), JobState.CANCELLED, ended=time.time(),
                                   reason=f"emergency stop by operator {user.name}")
            self.accounts.audit(user, "emergency stop", None if not active else int(active[0]["id"]), tx=tx)
        if self.arena is not None:
            self.arena.emergency_stop()
        self.notify()
        return self.arena_state(user)

    def release_arena(self, user: User) -> dict[str, Any]:
        """Release the emergency stop: the arena takes the next waiting job."""
        self._require_operator(user)
        with self.db.transaction() as tx:
            if self.db.setting("arena_stopped", "0") != "1":
                raise Conflict("the arena is not stopped", "arena")
            self.db.set_setting(tx, "arena_stopped", "0")
            self.db.set_setting(tx, "arena_attention", "")
            self.accounts.audit(user, "release emergency stop", tx=tx)
        self.notify()
        return self.arena_state(user)

    def arena_state(self, user: User) -> dict[str, Any]:
        """``{"stopped", "needs_operator": why|None, "alerts": {"job", "messages"}|None, "manual_approval", "running":
        job|None, "queue": [waiting jobs in order], "fleet": the fleet table|None}`` (the fleet:
        :meth:`.ArenaFleet.status`; the alerts: the running or last job's bypass revocation and contacts,
        :meth:`.ArenaRunner.alerts`)."""
        self._require_operator(user)
        running = self.db.query_one(f"{JOB_SELECT} WHERE j.state IN ('{JobState.SETTING_UP}', '{JobState.RUNNING}') ORDER BY j.id LIMIT 1")
        queue = self.db.query(f"{JOB_SELECT} WHERE j.state = '{JobState.IN_ARENA_QUEUE}' ORDER BY j.priority, j.id")
        fleet_status = getattr(self.arena, "fleet_status", None)
        alerts = getattr(self.arena, "alerts", None)
        return {"stopped": self.arena_stopped, "needs_operator": self.db.setting("arena_attention", "") or None,
                "alerts": None if alerts is None else alerts(),
                "manual_approval": self.manual_approval,
                "running": None if running is None else _job_dict(running),
                "queue": [_job_dict(r, k) for k, r in enumerate(queue)],
                "fleet": None if fleet_status is None else fleet_status()}

    def audit_log(self, user: User, limit: int = 200) -> list[dict[str, Any]]:
        self._require_operator(user)
        return self.accounts.audit_log(limit)

    # ------------------------------------------------------------------ workers and runner
    def claim_for_verification(self) -> dict[str, Any] | None:
        """The next queued job, now ``verifying`` (None when there is none): round-robin over the owners
        of queued jobs — the next owner (by user id) after the one served last, wrapping around — and that
        owner's oldest queued job, so one researcher's many jobs never make another's wait behind them all.
        The owner served last is kept in the database (``settings``), so the turn survives a restart."""
        with self.db.transaction() as tx:
            last = int(self.db.setting("verify_last_owner", "0"))
            row = tx.execute(f"SELECT id, user_id FROM jobs WHERE state = '{JobState.AWAITING_VERIFICATION}' "
                             "ORDER BY user_id <= ?, user_id, id LIMIT 1", (last,)).fetchone()
            if row is None:
                return None
            self.db.transition(tx, int(row["id"]), JobState.VERIFYING, sources=(JobState.AWAITING_VERIFICATION,))
            self.db.set_setting(tx, "verify_last_owner", str(int(row["user_id"])))
        self.notify()
        return _job_dict(self._row(int(row["id"])))

    def finish_verification(self, job_id: int, verdict: str, safety_score: float | None,
                            reasons: list[str]) -> None:
        """Record the verdict: ``rejected``, or ``approved`` (then ``waiting`` unless manual approval is on).
        A job cancelled meanwhile stays cancelled."""
        accepted = verdict != "rejected"
        with self.db.transaction() as tx:
            try:
                self.db.transition(tx, job_id, JobState.AWAITING_APPROVAL if accepted else JobState.REJECTED, sources=(JobState.VERIFYING,),
                                   # S of a rejected script says nothing (it may never have moved a robot)
                                   verdict=verdict, safety_score=safety_score if accepted else None,
                                   reason=None if accepted else "; ".join(reasons)[:4000],
                                   ended=None if accepted else time.time())
            except TransitionConflict:
                return
            pending = tx.execute(f"SELECT {_PENDING_SQL} AS p FROM jobs WHERE id = ?", (job_id,)).fetchone()["p"]
            if accepted and pending:  # a verdict alone never removes protection: an operator decides
                tx.execute("UPDATE jobs SET reason = ? WHERE id = ?", (BYPASS_WAIT, job_id))
            elif accepted and self.db.setting("manual_approval", "0") != "1":
                self.db.transition(tx, job_id, JobState.IN_ARENA_QUEUE, sources=(JobState.AWAITING_APPROVAL,))
        self.notify()

    def fail_verification(self, job_id: int, reason: str) -> None:
        """Verification could not run (infrastructure): the job is ``rejected`` with the reason."""
        self.finish_verification(job_id, "rejected", None, [f"verification could not run: {reason}"])

    def verifying_cancelled(self, job_id: int) -> bool:
        row = self.db.query_one("SELECT state FROM jobs WHERE id = ?", (job_id,))
        return row is None or row["state"] != JobState.VERIFYING

    def bypass_allowed(self, job: dict[str, Any]) -> bool:
        """Run ``job`` without the barrier (with the guard): verification allowed it, the manifest asked, no operator
        forbade it and an operator approved this job's bypass."""
        return (job["verdict"] == BYPASS_VERDICT and bool(job["request_no_barrier"]) and not job["barrier_forbidden"]
                and job.get("bypass_decision") == "approved")

    def claim_for_arena(self, admit: Callable[[dict[str, Any]], str | None] | None = None) -> dict[str, Any] | None:
        """The first waiting job, now ``setting up`` — None when there is none or the arena is stopped.

        ``admit(job)`` (the arena: are N charged robots free?) returns None to go ahead, or why the job
        must wait: it stays first in the queue, ``waiting``, with that ``reason`` (jobs run in queue order:
        a smaller job behind it does not overtake it). ``admit`` runs outside the database transaction.
        """
        first = f"{JOB_SELECT} WHERE j.state = '{JobState.IN_ARENA_QUEUE}' ORDER BY j.priority, j.id LIMIT 1"
        if admit is not None:
            if self.arena_stopped:
                return None
            row = self.db.query_one(first)
            if row is None:
                return None
            why = admit(_job_dict(row))
            if why is not None:
                self._waiting_reason(int(row["id"]), why[:4000])
                return None
            admitted = int(row["id"])
        with self.db.transaction() as tx:
            if self.db.setting("arena_stopped", "0") == "1":
                return None
            row = tx.execute(first).fetchone()
            if row is None or (admit is not None and int(row["id"]) != admitted):
                return None  # the queue changed meanwhile: the arena asks again
            job = _job_dict(row)
            bypass = self.bypass_allowed(job)
            self.db.transition(tx, int(row["id"]), JobState.SETTING_UP, sources=(JobState.IN_ARENA_QUEUE,), started=time.time(),
                               bypass=int(bypass), reason=None)
        self.notify()
        return _job_dict(self._row(int(row["id"])))

    def _waiting_reason(self, job_id: int, reason: str) -> None:
        """Say why a waiting job does not start yet (shown with the job; cleared when it is claimed)."""
        with self.db.transaction() as tx:
            cur = tx.execute(f"UPDATE jobs SET reason = ? WHERE id = ? AND state = '{JobState.IN_ARENA_QUEUE}' AND "
                             "COALESCE(reason, '') != ?", (reason, job_id, reason))
        if cur.rowcount:
            self.notify()

    def arena_needs_operator(self, message: str) -> None:
        """The arena cannot look after itself (a return to the chargers failed): it stops (no job starts,
        as after an emergency stop) and ``message`` (the robots named) is shown to operators until one
        releases it (:meth:`release_arena`)."""
        with self.db.transaction() as tx:
            self.db.set_setting(tx, "arena_stopped", "1")
            self.db.set_setting(tx, "arena_attention", message[:4000])
        self.notify()

    def mark_running(self, job_id: int) -> bool:
        """``setting up → running``; False if the job was cancelled (or e-stopped) meanwhile."""
        with self.db.transaction() as tx:
            try:
                self.db.transition(tx, job_id, JobState.RUNNING, sources=(JobState.SETTING_UP,))
            except TransitionConflict:
                return False
        self.notify()
        return True

    def finish_run(self, job_id: int, state: str, reason: str | None) -> str:
        """End a run (``done``/``failed``/``cancelled``) unless it already ended (cancelled, e-stopped):
        the job's final state."""
        with self.db.transaction() as tx:
            try:
                self.db.transition(tx, job_id, state, sources=ACTIVE, ended=time.time(), reason=reason)
            except TransitionConflict as exc:
                return str(exc.state)
        self.notify()
        return state

    def set_exports(self, job_id: int, state: str) -> None:
        """Where the job's exports are: ``"writing"``, ``"ready"`` or ``"failed"`` (:mod:`.exports`)."""
        with self.db.transaction() as tx:
            tx.execute("UPDATE jobs SET exports = ? WHERE id = ?", (state, int(job_id)))
        self.notify()

    def exports_in(self, state: str) -> list[int]:
        """The ids of the jobs whose exports are in ``state``, oldest first."""
        return [int(r["id"]) for r in self.db.query("SELECT id FROM jobs WHERE exports = ? ORDER BY id", (state,))]

    def job_state(self, job_id: int) -> str | None:
        if not valid_id(job_id):
            return None
        row = self.db.query_one("SELECT state FROM jobs WHERE id = ?", (int(job_id),))
        return None if row is None else str(row["state"])

    def recover_on_start(self) -> list[int]:
        """After a restart: jobs found on the arena become ``interrupted`` (their ids are returned, for the
        runner to recover their recordings); jobs found ``verifying`` go back to ``awaiting verification``."""
        with self.db.transaction() as tx:
            ids = [int(r["id"]) for r in tx.execute(
                f"SELECT id FROM jobs WHERE state IN ({', '.join('?' * len(ACTIVE))})", ACTIVE).fetchall()]
            for jid in ids:
                self.db.transition(tx, jid, JobState.INTERRUPTED, sources=ACTIVE, ended=time.time(),
                                   reason="the server stopped during the run (partial recording kept)")
            for r in tx.execute(f"SELECT id FROM jobs WHERE state = '{JobState.VERIFYING}'").fetchall():
                self.db.transition(tx, int(r["id"]), JobState.AWAITING_VERIFICATION, sources=(JobState.VERIFYING,))
        return ids

    def close(self) -> None:
        self.db.close()

