"""The retention sweep: a thread that deletes old results now and then (``swarmdeck server --retain-days D``).

Every ``period_s`` (first at start) it calls :meth:`.PortalService.sweep_results`: the folders of jobs that
ended more than D days ago (script, recording, exports, logs, reports) are deleted; each job's row stays,
with ``results_deleted`` (its page and ``swarmdeck jobs`` say when). A sweep that fails (a disk error) is
counted and tried again next period; it never stops the server.
"""
from __future__ import annotations

import sqlite3

from swarmdeck.console.portal.service import PortalService
from swarmdeck.core.service_thread import ServiceThread


class RetentionSweeper:
    """Runs :meth:`PortalService.sweep_results` every ``period_s`` s on a daemon thread: :meth:`start`, :meth:`stop`."""

    def __init__(self, service: PortalService, *, period_s: float = 3600.0) -> None:
        self.service, self.period_s = service, float(period_s)
        self._thread = ServiceThread(self._run, "swarmdeck-portal-retention", join_timeout=10.0)
        self.swept: list[int] = []
        self.errors = 0

    def start(self) -> RetentionSweeper:
        """Start sweeping (the first sweep at once); idempotent."""
        self._thread.start()
        return self

    def stop(self, timeout: float = 10.0) -> None:
        """Stop sweeping and join the thread (up to ``timeout`` s); idempotent."""
        self._thread.stop(timeout)

    def _run(self) -> None:
        while not self._thread.stopping:
            try:
                self.swept.extend(self.service.sweep_results())
            except (OSError, sqlite3.Error):
                self.errors += 1
            self._thread.wait(self.period_s)
