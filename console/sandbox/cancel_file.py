"""The cancel file of a batch of sandboxed runs: how a cancel reaches runs under way in any worker on this machine.

Each run (:class:`~swarmdeck.console.sandbox.verification.RunTask` ``cancel_path``) stops at its next tick once the
file exists. :func:`cancel_file` makes a fresh folder for it, watches the caller's event (every 0.1 s, in a thread
of its own) and touches the file when the event is set; ``cancelled()`` does the same check at once, for loops that
poll. Verification and sweeps share it.
"""
from __future__ import annotations

import shutil
import tempfile
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from swarmdeck.core.service_thread import ServiceThread

#: how often (s) the watcher looks at the event
WATCH_PERIOD_S = 0.1


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
