"""Verification workers: jobs awaiting verification → ``verifying`` → ``rejected`` | ``awaiting approval`` (then ``in arena queue``).

One thread (:class:`VerificationWorkers`) claims the next queued job (round-robin
across researchers: :meth:`~.service.PortalService.claim_for_verification`) and
verifies it — with the job's declared robot count and start poses, within a wall-time
budget derived from its declared duration — with :func:`swarmdeck.console.sandbox.verification.verify` on the
executor (``--workers W``: a local process pool of W; ``--ray ADDRESS``: a Ray
cluster), which runs the job's runs in parallel. The report goes to
``DIR/jobs/<id>/report.json`` and ``report.html``, the verdict to the job. A job
cancelled while it verifies stops within a tick of each run (the verification's
cancel event). Infrastructure failures (no confinement, a Ray worker lost) reject
the job with the reason, and the worker goes on with the next one.
"""
from __future__ import annotations

import json
import threading
from contextlib import nullcontext
from typing import Any, cast

from swarmdeck.console.portal.files import write_private
from swarmdeck.console.portal.job import Job
from swarmdeck.console.portal.jobfiles import WORST_CASE
from swarmdeck.console.portal.service import PortalService
from swarmdeck.console.sandbox.confinement import ConfinementUnavailable, SandboxLimits
from swarmdeck.console.sandbox.report_html import render_html
from swarmdeck.console.sandbox.verification import VerificationCancelled, VerificationConfig, verify
from swarmdeck.core.obstacles import Obstacles
from swarmdeck.core.service_thread import ServiceThread


def make_executor(workers: int | None = None, ray: str | None = None) -> Any:
    """The verification executor: a Ray cluster at ``ray``, else a local pool of ``workers`` processes."""
    from swarmdeck.console.sandbox.executors import LocalPoolExecutor, RayExecutor

    return RayExecutor(ray) if ray else LocalPoolExecutor(workers)


class VerificationWorkers:
    """The threads that verify queued jobs (each job's runs in parallel on the executor).

    ``concurrent``: how many jobs are verified at once (one thread each, all on the one executor). With 1, a job
    waits for the one before it to end — and a verification cannot end before its paced run's declared duration of
    real time, during which that run mostly waits; with 2, the next job's computing runs use the cores meanwhile
    (bench/RESULTS.md "verification queue"). The executor's workers (a local pool's processes and their fork
    servers) are kept while the threads run (:meth:`~swarmdeck.console.sandbox.executors.LocalPoolExecutor.kept`).
    """

    def __init__(self, service: PortalService, executor: Any, *, poll_s: float = 1.0,
                 obstacles: Obstacles | None = None, concurrent: int = 1) -> None:
        if isinstance(concurrent, bool) or not isinstance(concurrent, int) or concurrent < 1:
            raise ValueError(f"concurrent must be a positive integer (jobs verified at once), got {concurrent!r}")
        self.service, self.executor, self.poll_s = service, executor, float(poll_s)
        self.obstacles = obstacles  # the arena's line-segment obstacles: every verification run has them
        self._threads = [ServiceThread(self._run, "swarmdeck-portal-verify" + (f"-{k}" if k else ""),
                                       join_timeout=10.0, wake=self.service.notify) for k in range(concurrent)]
        self._thread = self._threads[0]
        self._count_lock = threading.Lock()
        self.verified = 0
        self.errors = 0

    def _count(self, verified: int = 0, errors: int = 0) -> None:
        with self._count_lock:  # several threads count
            self.verified += verified
            self.errors += errors

    def start(self) -> VerificationWorkers:
        """Start verifying queued jobs; idempotent."""
        for thread in self._threads:
            thread.start()
        return self

    def stop(self, timeout: float = 10.0) -> None:
        """Stop (a job being verified is cancelled within a tick) and join the threads (up to ``timeout`` s each)."""
        for thread in self._threads:
            thread.stop_event.set()  # all asked first: they stop together
        for thread in self._threads:
            thread.stop(timeout)

    def _run(self) -> None:
        kept = getattr(self.executor, "kept", None)  # one pool (warm workers) for every job, not one per job
        with kept() if kept is not None else nullcontext():
            while not self._thread.stopping:
                job = self.service.claim_for_verification()
                if job is None:
                    self.service.wait_for_change(self.poll_s)
                    continue
                self.verify_job(job)

    def config_for(self, job: Job) -> VerificationConfig:
        """The job's verification: its declared robots, duration and start poses, in the arena (or region of a
        divided floor) it will get (:meth:`~.service.PortalService.job_bounds`), as the arena will run it;
        each run's wall time is bounded by the declared duration (``VerificationConfig.run_wall_s``)."""
        cfg = self.service.config
        # rows [x, y, θ]: submission stored them checked (N, 3) (console.sandbox.start_poses.check_initial_poses)
        poses = cast("tuple[tuple[float, float, float], ...] | None", job.initial_poses)
        return VerificationConfig(n_robots=job.robots, duration=job.duration, runs=cfg.verify_runs,
                                  epsilon=cfg.verify_epsilon, confidence=cfg.verify_confidence,
                                  falsify_budget=cfg.verify_falsify_budget,
                                  seed=cfg.verify_seed + int(job.id), trusted=cfg.trusted,
                                  jail=cfg.jail(),
                                  limits=SandboxLimits(tick_s=cfg.tick_budget_s),
                                  initial_poses=poses, obstacles=self.obstacles,
                                  bounds=self.service.job_bounds(job))

    def verify_job(self, job: Job) -> None:
        """Verify one claimed job and record the verdict (never raises); a sweep job's runs instead
        (:meth:`sweep_job`)."""
        if job.sweep is not None:
            self.sweep_job(job)
            return
        service, job_id = self.service, int(job.id)
        cancel = threading.Event()

        watcher = self._watch(job_id, cancel)
        try:
            script, entry = service.script(job)
            # messages name the file the researcher uploaded, not the name the portal stored it under
            names = [job.script] if job.kind == "py" else None
            report = verify([script], self.config_for(job), self.executor, cancel=cancel, entry=entry, names=names,
                            worst_case_dir=service.job_dir(job_id), worst_case_name=WORST_CASE, params=job.params)
        except VerificationCancelled as exc:
            service.record_verification_cpu(job_id, exc.cpu_s)  # a cancel does not make the CPU free
            return  # cancelled: the job is already cancelled (or requeued on restart)
        except (ValueError, ConfinementUnavailable, RuntimeError, ConnectionError, OSError) as exc:
            self._count(errors=1)
            service.fail_verification(job_id, str(exc))
            return
        finally:
            watcher.stop()
        data = report.to_dict()
        service.record_verification_cpu(job_id, report.cpu_s)
        folder = service.job_dir(job_id)
        if (folder / WORST_CASE).is_file():
            (folder / WORST_CASE).chmod(0o600)  # like every result file (.files)
        write_private(folder / "report.json", json.dumps(data, indent=1))
        try:
            write_private(folder / "report.html", render_html(data))
        except Exception:  # noqa: BLE001 - the HTML is a convenience; the JSON is the report
            self._count(errors=1)
        self._count(verified=1)
        service.finish_verification(job_id, report.verdict, report.safety_score, data["reasons"])


    def _watch(self, job_id: int, cancel: threading.Event) -> ServiceThread:
        """A thread that sets ``cancel`` once the job is cancelled (or the service stops)."""
        service = self.service

        def watch() -> None:  # the job cancelled (or the service stopping) cancels the verification
            while not watcher.wait(0.2):
                if self._thread.stopping or service.verifying_cancelled(job_id):
                    cancel.set()
                    return

        watcher = ServiceThread(watch, f"swarmdeck-portal-verify-watch-{job_id}", join_timeout=None)
        return watcher.start()  # started once ``watcher`` is bound: watch() reads it

    def sweep_job(self, job: Job) -> None:
        """Run a claimed sweep job's runs on the executor (:mod:`.sweep_job`), charge their CPU to the owner's daily
        verification limit, and end it ``done`` or ``failed`` (never raises). A cancelled sweep stops within a tick
        of each run; the runs finished before are kept in its folder."""
        from swarmdeck.console.portal.sweep_job import SweepRequest, parse_request, run_job
        from swarmdeck.console.sandbox.verification import load_script
        from swarmdeck.console.sweep.campaign import SweepIncomplete

        service, job_id = self.service, int(job.id)
        cancel = threading.Event()
        watcher = self._watch(job_id, cancel)
        try:
            request: SweepRequest = parse_request(job.sweep, service.config.limits)
            script, entry = service.script(job)
            bundle = load_script(script, entry)
            result = run_job(request, bundle, self.config_for(job), service.job_dir(job_id), self.executor, cancel)
        except SweepIncomplete as exc:
            service.record_verification_cpu(job_id, exc.cpu_s)  # a cancel does not make the CPU free
            if not cancel.is_set():
                self._count(errors=1)
                service.finish_sweep(job_id, False, str(exc))
            return
        except Exception as exc:  # noqa: BLE001 - a sweep that cannot run fails with the reason; the worker goes on
            self._count(errors=1)
            service.finish_sweep(job_id, False, f"the sweep could not run: {exc}")
            return
        finally:
            watcher.stop()
        service.record_verification_cpu(job_id, sum(result.cpu_s))
        self._count(verified=1)
        said = [f"{len(result.rows)} runs, {result.failed} failed"] if result.failed else []
        if request.promote is not None:
            said.append(self._promote(job, request, result))
        service.finish_sweep(job_id, True, "; ".join(said) or None)

    def _promote(self, job: Job, request: Any, result: Any) -> str:
        """Submit the finished sweep's best point as an arena job (:meth:`.service.PortalService.promote`); what
        happened, for the sweep's reason line (never raises: a sweep that ran is done whatever the promotion)."""
        from swarmdeck.console.sweep.best import best_point

        wanted = request.promote
        try:
            best = best_point(result.plan, result.rows, wanted)
            if best is None:
                return (f"best point not promoted: no point has {wanted.column} from runs that all finished")
            robots = best.robots if best.robots is not None else job.robots
            promoted = self.service.promote(job, best.params, robots, request.duration,
                                            f"{request.name}: best {wanted.column} ({wanted.goal})")
        except Exception as exc:  # noqa: BLE001 - quota, no arena, disabled account: said on the sweep, never raised
            self._count(errors=1)
            return f"best point not promoted: {exc}"
        return f"best point ({best.describe(wanted)}) promoted to job {promoted.id}"
