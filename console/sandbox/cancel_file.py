"""The cancel file of a batch of sandboxed runs: how a cancel reaches runs under way in any worker on this machine.

Each run (:class:`~swarmdeck.console.sandbox.verification.RunTask` ``cancel_path``) stops at its next tick once it
saw the file (:class:`CancelSeen`: looked for at most every :data:`CHECK_PERIOD_S`). :func:`cancel_file` makes a fresh folder for it, watches the caller's event (every 0.1 s, in a thread
of its own) and touches the file when the event is set; ``cancelled()`` does the same check at once, for loops that
poll. Verification and sweeps share it.
"""
from __future__ import annotations

import os
import shutil
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from swarmdeck.core.service_thread import ServiceThread

#: how often (s) the watcher looks at the event
WATCH_PERIOD_S = 0.1
#: how often (s) a run looks for the cancel file (a ``stat`` every tick cost ≈ 2–3 % of a 20-robot run's CPU on
#: this VM: bench/RESULTS.md "sandbox per tick")
CHECK_PERIOD_S = 0.05


class CancelSeen:
    """``cancelled()`` of a run: whether the cancel file ``path`` exists, looked for at most every ``period`` s
    (monotonic clock; the first call looks) and true for good once seen."""

    def __init__(self, path: str, period: float = CHECK_PERIOD_S) -> None:
        self.path, self.period = path, float(period)
        self._next = 0.0
        self._seen = False

    def __call__(self) -> bool:
        if self._seen:
            return True
        now = time.monotonic()
        if now >= self._next:
            self._next = now + self.period
            self._seen = os.path.exists(self.path)
        return self._seen


@contextmanager
def cancel_file(cancel: threading.Event | None, name: str) -> Iterator[tuple[str, Callable[[], bool]]]:
    """Yield ``(path, cancelled)``: the cancel file's path (not yet there) and a check that touches it once
    ``cancel`` is set and says whether it is. ``name``: the watcher thread's name. The folder is removed on exit."""
    folder = Path(tempfile.mkdtemp(prefix="swarmdeck-cancel-"))
    path = str(folder / "cancel")

    def cancelled() -> bool:
        if cancel is not None and cancel.is_set():
            Path(path).touch()  # runs under way (in any worker on this machine) stop at their next tick
            return True
        return False

    def watch() -> None:
        while not watcher.wait(WATCH_PERIOD_S) and not cancelled():
            pass

    watcher = ServiceThread(watch, name, join_timeout=None)
    watcher.start()
    try:
        yield path, cancelled
    finally:
        watcher.stop()
        shutil.rmtree(folder, ignore_errors=True)
