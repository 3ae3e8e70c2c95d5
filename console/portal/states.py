"""The portal's job states, named for what they mean, in one place (issue 26).

:class:`JobState` is a ``str`` enum: a member *is* its string, so the database column, the JSON API and
the pages keep plain, readable strings, and code compares with the members. The database's state machine
(:data:`swarmdeck.console.portal.db.TRANSITIONS`), the service, the workers, the arena runner, the pages
and the CLI client all use these. This module imports nothing of swarmdeck's, so the thin client commands
(``swarmdeck jobs`` …) stay fast.

What each state means is in one table, the README's portal section ("A job's state").

The names until schema version 4 were ``queued`` (now ``awaiting verification``), ``approved`` (now
``awaiting approval``) and ``waiting`` (now ``in arena queue``); migration 5 renames stored jobs.
"""
from __future__ import annotations

from enum import StrEnum


class JobState(StrEnum):
    """A job's state (module docstring); the value is what the database, the API and the pages show."""

    AWAITING_VERIFICATION = "awaiting verification"
    VERIFYING = "verifying"
    REJECTED = "rejected"
    AWAITING_APPROVAL = "awaiting approval"
    IN_ARENA_QUEUE = "in arena queue"
    SETTING_UP = "setting up"
    RUNNING = "running"
    DONE = "done"
    FAILED = "failed"
    CANCELLED = "cancelled"
    INTERRUPTED = "interrupted"
    HELD = "held"


#: the states a job never leaves
FINAL: tuple[JobState, ...] = (JobState.REJECTED, JobState.DONE, JobState.FAILED, JobState.CANCELLED,
                               JobState.INTERRUPTED)
#: the job is on the arena
ACTIVE: tuple[JobState, ...] = (JobState.SETTING_UP, JobState.RUNNING)
#: the names before migration 5 -> the names now
RENAMED: dict[str, JobState] = {"queued": JobState.AWAITING_VERIFICATION, "approved": JobState.AWAITING_APPROVAL,
                                "waiting": JobState.IN_ARENA_QUEUE}
