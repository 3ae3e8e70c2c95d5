"""Per-researcher limits, checked when a job is submitted: jobs not yet finished, verification CPU a day, results disk.

A submission over a limit is refused with the limit named and the researcher's current value
(``you have 25 jobs not yet finished …; the limit is 25``):

* **unfinished jobs** (awaiting verification, verifying, awaiting approval, in arena queue, held, setting up, running) — 429: wait for one
  to end or cancel one. Counted inside the submission's own transaction, so two submissions at once cannot
  both pass the last free place.
* **verification CPU seconds in the last 24 h** (the trusted side's and the jail's CPU of every run, as
  :func:`swarmdeck.console.sandbox.verification.run_task` measures it, recorded when the verdict is) — 429,
  saying when new jobs are accepted again.
* **results on disk** (every file under the researcher's jobs' folders) — 403: delete nothing yourself; the
  lab's retention policy (``swarmdeck server --retain-days D``) or an operator frees space.

Operators are not limited. ``None`` switches a limit off. A job that is already accepted is never stopped
by a limit (its results may take a researcher over the disk quota: the next submission is refused).
"""
from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path

from swarmdeck.console.portal.errors import QuotaExceeded, RateLimited

DAY_S = 86400.0


@dataclass(frozen=True)
class Quotas:
    """Per-researcher limits (None: no limit).

    Attributes:
        max_unfinished_jobs: jobs a researcher may have that have not finished (any state but rejected, done,
            failed, cancelled, interrupted).
        verify_cpu_s_per_day: verification CPU seconds of a researcher's jobs in any 24 h.
        results_bytes: bytes a researcher's jobs' folders may hold (scripts, recordings, exports, logs).
    """

    max_unfinished_jobs: int | None = 25
    verify_cpu_s_per_day: float | None = 4 * 3600.0
    results_bytes: int | None = 2_000_000_000


def folder_bytes(folder: Path) -> int:
    """Bytes of the regular files under ``folder`` (0 if it does not exist); symlinks are not followed."""
    total = 0
    stack = [str(folder)]
    while stack:
        try:
            entries = list(os.scandir(stack.pop()))
        except OSError:
            continue
        for entry in entries:
            try:
                if entry.is_dir(follow_symlinks=False):
                    stack.append(entry.path)
                elif entry.is_file(follow_symlinks=False):
                    total += entry.stat(follow_symlinks=False).st_size
            except OSError:
                continue
    return total


def _size(n: int) -> str:
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            return f"{n / scale:.1f} {unit}"
    return f"{n} bytes"


def results_bytes(job_ids: list[int], jobs_folder: Path) -> int:
    """Bytes under the folders of jobs ``job_ids`` in ``jobs_folder`` (a researcher's results on disk)."""
    return sum(folder_bytes(jobs_folder / str(int(j))) for j in job_ids)


def usage(unfinished: int, cpu: list[tuple[float, float]], job_ids: list[int], quotas: Quotas,
          jobs_folder: Path) -> dict[str, dict[str, float | None]]:
    """Where a researcher stands: ``{"unfinished_jobs" | "verify_cpu_s_today" | "results_bytes": {"used",
    "limit"}}`` (limit None: none) from their unfinished-job count, their verification usage (when, CPU s) of the
    last 24 h and their jobs whose results were not deleted."""
    return {
        "unfinished_jobs": {"used": int(unfinished), "limit": quotas.max_unfinished_jobs},
        "verify_cpu_s_today": {"used": round(sum(c for _, c in cpu), 1), "limit": quotas.verify_cpu_s_per_day},
        "results_bytes": {"used": results_bytes(job_ids, jobs_folder), "limit": quotas.results_bytes},
    }


def check_disk(job_ids: list[int], quotas: Quotas, jobs_folder: Path) -> None:
    """Refuse a new job when the researcher's jobs (``job_ids``: results not deleted) hold
    ``results_bytes`` or more under ``jobs_folder``: :class:`QuotaExceeded` (403) naming both. Walks the folders:
    call it outside the submission's transaction."""
    if quotas.results_bytes is None:
        return
    used = results_bytes(job_ids, jobs_folder)
    if used >= quotas.results_bytes:
        raise QuotaExceeded(f"your jobs' files take {_size(used)}; the limit is {_size(quotas.results_bytes)}: download what you need and ask the lab to "
                            "free space (results are kept as the lab's retention policy says)", "results_bytes")


def check_counts(quotas: Quotas, unfinished: int, cpu: list[tuple[float, float]], now: float) -> None:
    """Refuse a new job of a researcher with ``unfinished`` jobs not yet ended and verification usage ``cpu``
    ((when, CPU s) of the last 24 h, oldest first; read inside the submission's transaction) over the
    unfinished-jobs or the daily verification-CPU limit: :class:`RateLimited` (429) naming the limit and the
    current value."""
    if quotas.max_unfinished_jobs is not None and unfinished >= quotas.max_unfinished_jobs:
        raise RateLimited(f"you have {unfinished} jobs not yet finished (awaiting verification or approval, "
                          f"verifying, in arena queue or running); the limit is {quotas.max_unfinished_jobs}: wait "
                          "for one to end, or cancel one", "max_unfinished_jobs")
    if quotas.verify_cpu_s_per_day is not None:
        used = sum(c for _, c in cpu)
        if used >= quotas.verify_cpu_s_per_day:
            left, again = used, now
            for t, c in cpu:  # the oldest usage leaves the 24 h window first
                left -= c
                again = t + DAY_S
                if left < quotas.verify_cpu_s_per_day:
                    break
            raise RateLimited(f"verification of your jobs used {used:.0f} CPU s in the last 24 h; the limit is "
                              f"{quotas.verify_cpu_s_per_day:.0f} CPU s a day: new jobs are accepted again from "
                              f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime(again))}", "verify_cpu_s_per_day")
