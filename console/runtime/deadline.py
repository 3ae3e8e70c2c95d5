"""Calling untrusted code with a per-tick deadline (a user's behaviour script).

:class:`DeadlineCaller` runs each call on one daemon worker thread and waits at
most ``budget`` seconds for it. A call that does not return in time is
*abandoned for that tick*: :meth:`DeadlineCaller.call` raises
:class:`TickBudgetExceeded` and the control loop stops the robots for the tick
(its one error policy). While the abandoned call is still running, every later
call is abandoned at once, without waiting, so a hanging script costs the loop
one budget once and nothing after that: the loop keeps its rate. When the late
call finally returns its result is thrown away and the next tick calls again.

A machine starved of CPU is not the script's fault: when the call has had less
than its budget of CPU and was waiting for a CPU rather than blocked by itself
(the worker had not started it, or the kernel's ``schedstat`` shows it waiting
on a run queue, or it is runnable now), the script is reported by what it did
the last time it got the CPU — its own error when it raised (an instantly
raising script under load is reported by its exception, never as "did not
return within its tick budget") — or the tick is abandoned saying the machine
is overloaded.

What is *not* done: Python cannot kill a thread, so a script that never
returns keeps its worker thread (a daemon: it never holds up the process's exit)
until the process ends; switching to another behaviour leaves it behind. Moving
user scripts into a sandboxed child process that can be killed is a later issue
(``swarmdeck verify``'s bubblewrap sandbox).
"""
from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import Any

from swarmdeck.core.errors import SwarmdeckError


class TickBudgetExceeded(RuntimeError, SwarmdeckError):
    """A call was abandoned: it did not return within its budget, or an earlier call still runs."""


class _Call:
    def __init__(self, fn: Callable[..., Any], args: tuple[Any, ...]) -> None:
        self.fn, self.args = fn, args
        self.done = threading.Event()
        self.result: Any = None
        self.error: BaseException | None = None
        self.abandoned = False
        self.started: tuple[float, float, float] | None = None  # (monotonic, CPU, run-queue wait) s at the start


def _state(native_id: int | None) -> str:
    """The scheduler state of a thread of this process ("R" runnable, "S" sleeping, …; "" when unknown)."""
    try:
        with open(f"/proc/self/task/{native_id}/stat", "rb") as fh:
            return fh.read().rsplit(b")", 1)[1].split()[0].decode()
    except (OSError, IndexError, UnicodeDecodeError):
        return ""


def _schedstat(native_id: int | None) -> tuple[float, float] | None:
    """(CPU time, time waiting on a run queue for a CPU) of a thread of this process, s; None where Linux's
    ``/proc/self/task/TID/schedstat`` is missing."""
    if native_id is None:
        return None
    try:
        with open(f"/proc/self/task/{native_id}/schedstat", "rb") as fh:
            cpu, wait = fh.read().split()[:2]
        return int(cpu) * 1e-9, int(wait) * 1e-9
    except (OSError, ValueError):
        return None


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
        self._last_error: Exception | None = None  # what the latest finished call raised (None: it returned)

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
                in_flight = self._running or self._pending
                assert in_flight is not None  # checked just above
                if self._starved(in_flight, budget):  # the machine, not the script, is slow
                    if self._last_error is not None:
                        raise self._last_error  # what the script did when it last got the CPU
                    raise TickBudgetExceeded("still waiting for the CPU since an earlier tick (the machine is "
                                             "overloaded); this tick abandoned")
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
                    if self._starved(job, budget):
                        # CPU starvation: the call had less than its budget of CPU. If the script raised last
                        # time, that is its error (not "too slow"); else say what happened.
                        if self._last_error is not None:
                            raise self._last_error
                        raise TickBudgetExceeded(f"got less than its tick budget of {budget * 1e3:.0f} ms of CPU "
                                                 "(the machine is overloaded); tick abandoned")
                    raise TickBudgetExceeded(f"did not return within its tick budget of {budget * 1e3:.0f} ms; "
                                             "tick abandoned")
        if isinstance(job.error, Exception):
            raise job.error
        if job.error is None:
            with self._lock:
                self._last_error = None
        if job.error is not None:  # SystemExit, KeyboardInterrupt from user code must not end the caller
            raise RuntimeError(f"raised {type(job.error).__name__}: {job.error}") from job.error
        return job.result

    def _starved(self, job: _Call, budget: float) -> bool:
        """True when ``job`` was starved of CPU rather than slow: the worker has not even started it, or it has
        had less than ``budget`` s of CPU and started less than half a budget ago, is runnable now (waiting for
        a CPU) or spent at least half of the time it did not run waiting for one (the kernel's run-queue wait). A call sleeping, waiting on I/O or
        on an Event is not starved: it is the script's own doing."""
        if job.started is None:
            return True
        thread = self._thread
        tid = None if thread is None else thread.native_id
        now = _schedstat(tid)
        if now is None:  # no scheduler statistics: judge by wall time alone
            return False
        wall0, cpu0, wait0 = job.started
        cpu, waited = now[0] - cpu0, now[1] - wait0
        wall = time.monotonic() - wall0
        idle = max(wall - cpu, 0.0)
        # started so late that it had under half its budget of time, or waiting for a CPU (run queue, runnable)
        return cpu < budget and (wall < 0.5 * budget or waited >= 0.5 * idle or _state(tid) == "R")

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
            stat = _schedstat(threading.get_native_id())
            job.started = (time.monotonic(), *(stat if stat is not None else (math.nan, math.nan)))
            try:
                job.result = job.fn(*job.args)
            except BaseException as exc:  # user code: handed to the caller, never kills the worker
                job.error = exc
            with self._lock:
                self._running = None
                err = job.error
                self._last_error = (err if isinstance(err, Exception) else
                                    RuntimeError(f"raised {type(err).__name__}: {err}") if err is not None else None)
                if job.abandoned:
                    self.late += 1
                    job.result = job.error = None
                job.done.set()
                self._wake.notify_all()
