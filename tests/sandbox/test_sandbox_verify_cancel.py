"""verify() is cancellable: setting the event stops the run under way and raises VerificationCancelled."""
import threading

import pytest

from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor
from swarmdeck.console.sandbox.verification import VerificationCancelled, VerificationConfig, verify

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")


def test_cancel_stops_a_long_verification(tmp_path):
    script = tmp_path / "s.py"
    script.write_text("def experiment(arena):\n    while True:\n        arena.step()\n")
    cancel = threading.Event()
    seen = []
    timer = threading.Timer(1.0, cancel.set)  # an hour of simulated time: only the cancel can end this test soon
    timer.start()
    try:
        with pytest.raises(VerificationCancelled):
            verify([script], VerificationConfig(n_robots=2, duration=3600.0, runs=2), SerialExecutor(),
                   on_progress=seen.append, cancel=cancel)
    finally:
        timer.cancel()
    assert len(seen) <= 1  # the run under way was stopped and no further run started
