"""A sweep job cancelled while its runs go stops them (within a tick of each run): it stays cancelled, the worker
counts no error, the CPU its runs used is charged to the researcher's daily limit, and what finished is kept."""
import time

import pytest

from swarmdeck.console.portal.service import PortalConfig, PortalService
from swarmdeck.console.portal.workers import VerificationWorkers
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

FOREVER = (b"from swarmdeck.devices import params\np = params(gain=1.0)\n"
           b"def experiment(arena):\n    while True:\n        arena.step()\n")


def wait_until(what: str, check, timeout: float = 120.0):
    deadline = time.monotonic() + timeout
    while not (found := check()):
        if time.monotonic() > deadline:
            raise AssertionError(f"{what}: not within {timeout} s")
        time.sleep(0.05)
    return found


def test_a_cancelled_sweep_stops_its_runs_and_is_charged_for_what_ran(tmp_path):
    svc = PortalService(PortalConfig(data=tmp_path / "data"))
    workers = VerificationWorkers(svc, SerialExecutor(), poll_s=0.1)
    try:
        user = svc.accounts.add_user("alice", "researcher")[0]
        job = svc.submit_sweep(user, "forever.py", FOREVER, {"params": ["gain=1,2"], "robots": 2, "duration": 600})
        workers.start()
        wait_until("the sweep started", lambda: svc.store.state(job.id) == "verifying")
        assert svc.cancel(user, job.id).state == "cancelled"
        # the worker is done with it once the CPU of its runs is recorded (SweepIncomplete.cpu_s)
        wait_until("the cancelled sweep's CPU was charged", lambda: svc.store.verification_cpu(user.id, 0.0))
        assert svc.store.state(job.id) == "cancelled" and workers.errors == 0 and workers.verified == 0
        assert sum(c for _, c in svc.store.verification_cpu(user.id, 0.0)) > 0  # the stopped run's CPU too
        report = (svc.job_dir(job.id) / "sweep" / "report.html").read_text()
        assert "INCOMPLETE: 0 of 2 runs finished" in report
    finally:
        workers.stop()
        svc.close()
