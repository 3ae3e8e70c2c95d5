"""The suite's watchdog (tests/watchdog.py) ends a test that outlives its timeout, names it, and
the run goes on.

The inner suite's first test is hung the way pytest-timeout cannot end: its timeout interrupts the
body, and the cleanup then waits again without a bound. Before the watchdog, such a test held the
whole run (and CI) until the job's own limit.
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parents[1]

INNER = '''
import time

import pytest


@pytest.mark.timeout(1)
def test_hangs_in_its_cleanup():
    try:
        time.sleep(60)
    finally:
        time.sleep(60)


def test_runs_after_it():
    assert True
'''


def test_a_test_hung_past_its_timeout_ends_its_worker_is_named_and_the_run_goes_on(tmp_path: Path) -> None:
    (tmp_path / "test_inner.py").write_text(INNER)
    (tmp_path / "pytest.ini").write_text("[pytest]\ntimeout = 30\n")
    env = dict(os.environ, PYTHONPATH=str(TESTS), SWARMDECK_TEST_GRACE_S="2")
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "watchdog", "-p", "no:cacheprovider", "-n", "1", "-q",
         "-p", "no:randomly", "test_inner.py"],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120,
    )
    out = done.stdout + done.stderr
    assert done.returncode == 1, out
    assert "1 failed, 1 passed" in out, out
    assert "crashed while running" in out and "test_hangs_in_its_cleanup" in out, out
    # the stacks the hung worker left, printed in the summary: the cleanup's sleep is named
    assert "hung: test_inner.py::test_hangs_in_its_cleanup" in out, out
    assert "in test_hangs_in_its_cleanup" in out, out
