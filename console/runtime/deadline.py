"""Calling untrusted code with a per-tick deadline (a user's behaviour script).

:class:`DeadlineCaller` runs each call on one daemon worker thread and waits at
most ``budget`` seconds for it. A call that does not return in time is
*abandoned for that tick*: :meth:`DeadlineCaller.call` raises
:class:`TickBudgetExceeded` and the control loop stops the robots for the tick
(its one error policy). While the abandoned call is still running, every later
call is abandoned at once, without waiting, so a hanging script costs the loop
one budget once and nothing after that: the loop keeps its rate. When the late
call finally returns its result is thrown away and the next tick calls again.

What is *not* done: Python cannot kill a thread, so a script that never
returns keeps its worker thread (a daemon: it never holds up the process's exit)
until the process ends; switching to another behaviour leaves it behind. Moving
user scripts into a sandboxed child process that can be killed is a later issue
(``swarmdeck verify``'s bubblewrap sandbox).
"""
from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any


class TickBudgetExceeded(RuntimeError):
    """A call was abandoned: it did not return within its budget, or an earlier call still runs."""


class _Call:
    def __init__(self, fn: Callable[..., Any], args: tuple[Any, ...]) -> None:
        self.fn, self.args = fn, args
        self.done = threading.Event()
        self.result: Any = None
        self.error: BaseException | None = None
        self.abandoned = False


class DeadlineCaller:
    """One worker thread that runs calls for a caller who waits at most a budget (s) for each.

    Counters (read them from any thread): ``calls`` started, ``timed_out`` calls
    that did not return within their budget (each cost the caller one budget of
    waiting), ``skipped`` calls refused at once because an abandoned call still
    ran, ``late`` abandoned calls that returned afterwards (result discarded).
    ``abandoned`` = ``timed_out`` + ``skipped``, the ticks lost.
    """

    def __init__(self, name: str = "swarmdeck-script") -> None:
        self.name = name
        self.calls = self.timed_out = self.skipped = self.late = 0
        self._lock = threading.Lock()
        self._pending: _Call | None = None      # handed to the worker, not yet taken
        self._running: _Call | None = None      # the call the worker is in (None: idle)
        self._wake = threading.Condition(self._lock)
        self._closed = False
        self._thread: threading.Thread | None = None

    @property
    def abandoned(self) -> int:
        return self.timed_out + self.skipped

    @property
    def busy(self) -> bool:
        """True while an abandoned call is still running."""
        with self._lock:
            return self._running is not None or self._pending is not None

    def call(self, fn: Callable[..., Any], *args: Any, budget: float) -> Any:
        """``fn(*args)`` on the worker thread; its result, or its exception re-raised (a BaseException
        such as SystemExit as a RuntimeError naming it).

        Raises TickBudgetExceeded if it does not return within ``budget`` s (the
        call goes on running; see the module docstring) or if an earlier abandoned
        call is still running (then nothing is started and nothing is waited for).
        """
        with self._lock:
            if self._closed:
                raise RuntimeError(f"{self.name}: closed")
            if self._running is not None or self._pending is not None:
                self.skipped += 1
                raise TickBudgetExceeded("still running from an earlier tick; this tick abandoned")
            job = _Call(fn, args)
            self._pending = job
            self.calls += 1
            if self._thread is None:
                self._thread = threading.Thread(target=self._work, name=self.name, daemon=True)
                self._thread.start()
            self._wake.notify_all()
        if not job.done.wait(budget):
            with self._lock:
                if not job.done.is_set():
                    self.timed_out += 1
                    job.abandoned = True  # its late result will be discarded
                    raise TickBudgetExceeded(f"did not return within its tick budget of {budget * 1e3:.0f} ms; "
                                             "tick abandoned")
        if isinstance(job.error, Exception):
            raise job.error
        if job.error is not None:  # SystemExit, KeyboardInterrupt from user code must not end the caller
            raise RuntimeError(f"raised {type(job.error).__name__}: {job.error}") from job.error
        return job.result

    def wait_idle(self, timeout: float | None = None) -> bool:
        """Block until no call runs (True) or ``timeout`` s pass (False). For tests and shutdown."""
        with self._lock:
            return self._wake.wait_for(lambda: self._running is None and self._pending is None, timeout)

    def close(self) -> None:
        """Stop the worker once it is idle (a hanging call keeps it; it is a daemon thread)."""
        with self._lock:
            self._closed = True
            self._wake.notify_all()

    def _work(self) -> None:
        while True:
            with self._lock:
                self._wake.wait_for(lambda: self._pending is not None or self._closed)
                if self._pending is None:
                    return
                job, self._pending = self._pending, None
                self._running = job
            try:
                job.result = job.fn(*job.args)
            except BaseException as exc:  # user code: handed to the caller, never kills the worker
                job.error = exc
            with self._lock:
                self._running = None
                if job.abandoned:
                    self.late += 1
                    job.result = job.error = None
                job.done.set()
                self._wake.notify_all()
