"""A script that raises at once is reported with its own error even when the machine starves its worker of CPU,
never as "did not return within its tick budget". Real starvation: the worker thread runs with the SCHED_IDLE
policy on one CPU where three busy processes run (stopped and continued with SIGSTOP/SIGCONT), so it gets
that CPU only while they are stopped. The caller runs on another CPU."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time

import pytest

from swarmdeck.console.runtime.deadline import DeadlineCaller, TickBudgetExceeded

needs_two_cpus = pytest.mark.skipif(len(os.sched_getaffinity(0)) < 2, reason="needs two CPUs to starve one")


def boom():
    raise ValueError("boom")


class Hogs:
    """Three busy processes pinned to ``cpu``; ``on()`` / ``off()`` continue / stop them."""

    def __init__(self, cpu: int) -> None:
        self.procs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(3)]
        for p in self.procs:
            os.sched_setaffinity(p.pid, {cpu})

    def on(self) -> None:
        for p in self.procs:
            p.send_signal(signal.SIGCONT)

    def off(self) -> None:
        for p in self.procs:
            p.send_signal(signal.SIGSTOP)

    def kill(self) -> None:
        for p in self.procs:
            p.kill()
            p.wait()


def _report(caller: DeadlineCaller) -> str:
    try:
        caller.call(boom, budget=0.0165)
        return "returned"
    except ValueError as exc:
        return f"ValueError: {exc}"
    except TickBudgetExceeded as exc:
        return f"budget: {exc}"


@needs_two_cpus
def test_a_raising_script_is_reported_by_its_error_under_starvation():
    caller = DeadlineCaller("test-starved")
    assert caller.call(lambda: None, budget=10.0) is None  # the worker thread exists and is idle
    me, mine = threading.get_native_id(), os.sched_getaffinity(0)
    cpu = max(mine)
    hogs = Hogs(cpu)
    try:
        worker = caller._thread.native_id
        os.sched_setaffinity(worker, {cpu})
        os.sched_setscheduler(worker, os.SCHED_IDLE, os.sched_param(0))
        os.sched_setaffinity(me, mine - {cpu})
        time.sleep(0.2)  # the hogs are running
        first = _report(caller)  # starved from the start: nothing known about the script yet
        assert first == "ValueError: boom" or ("less than its tick budget" in first and "overloaded" in first), first
        hogs.off()  # the worker gets the CPU: the abandoned call raises, late
        assert caller.wait_idle(30.0)
        hogs.on()
        reports = []
        for _ in range(30):  # ticks of a 30 Hz loop under starvation
            reports.append(_report(caller))
            time.sleep(0.033)
        assert reports == ["ValueError: boom"] * 30, reports
        assert caller.timed_out + caller.skipped >= 1  # the worker was starved meanwhile
    finally:
        hogs.kill()
        os.sched_setaffinity(me, mine)
        caller.close()


def test_a_script_that_blocks_by_itself_is_still_over_budget():
    gate = threading.Event()
    caller = DeadlineCaller("test-blocked")
    with pytest.raises(ValueError):
        caller.call(boom, budget=10.0)  # the script raised once…
    with pytest.raises(TickBudgetExceeded, match="did not return within its tick budget"):
        caller.call(gate.wait, budget=0.05)  # …then waits on its own: too slow, not starved
    with pytest.raises(TickBudgetExceeded, match="still running from an earlier tick"):
        caller.call(boom, budget=0.05)
    gate.set()
    assert caller.wait_idle(10.0)
    caller.close()
