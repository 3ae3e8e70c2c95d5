"""The portal verifies several queued jobs at once (``VerificationWorkers(concurrent=J)``, ``swarmdeck server
--verify-concurrent``): a verification cannot end before its paced run's declared duration of real time, so with one
job at a time the next job's runs waited for that clock instead of using the cores."""
from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from typing import Any

import pytest
from portal_fixtures import SPIN, wait_for_state

from swarmdeck.console.portal.workers import VerificationWorkers
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor
from swarmdeck.console.sandbox.verification import run_task

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")


class Rendezvous(SerialExecutor):
    """The serial executor (real sandboxed runs), whose :meth:`run` first waits (at most ``wait_s``) until
    ``expected`` verifications are inside it at once, and records the most that were."""

    def __init__(self, expected: int, wait_s: float) -> None:
        self.expected, self.wait_s = expected, wait_s
        self.inside = 0
        self.most = 0
        self.changed = threading.Condition()

    def run(self, tasks: Sequence[Any], on_done: Callable[[int, dict[str, Any], int], None],
            cancelled: Callable[[], bool], fn: Callable[[Any], dict[str, Any]] = run_task) -> list[dict | None]:
        with self.changed:
            self.inside += 1
            self.most = max(self.most, self.inside)
            self.changed.notify_all()
            self.changed.wait_for(lambda: self.inside >= self.expected, timeout=self.wait_s)
        try:
            return super().run(tasks, on_done, cancelled, fn)
        finally:
            with self.changed:
                self.inside -= 1


def test_two_queued_jobs_are_verified_at_once_and_both_get_their_verdicts(portal):
    executor = Rendezvous(expected=2, wait_s=60.0)
    with pytest.raises(ValueError, match="concurrent must be a positive integer"):
        VerificationWorkers(portal.service, executor, concurrent=0)
    workers = VerificationWorkers(portal.service, executor, poll_s=0.2, concurrent=2).start()
    try:
        ids = [portal.submit(who, source=SPIN, duration=0.5).json()["id"] for who in ("alice", "bob")]
        for who, jid in zip(("alice", "bob"), ids):
            with portal.client(who) as c:
                job = wait_for_state(c, jid, ("in arena queue", "rejected"), timeout=180)
                assert job["state"] == "in arena queue", job
    finally:
        workers.stop()
    assert executor.most == 2, "the second job waited for the first one's verification to end"
    assert (workers.verified, workers.errors) == (2, 0)
