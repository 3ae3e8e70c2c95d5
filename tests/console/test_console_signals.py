"""SIGTERM and SIGHUP stop `swarmdeck console` like Ctrl-C: robots stopped, the recording closed with
its summary (issue 14, item 14). A real console process, a real signal."""
from __future__ import annotations

import os
import signal
import subprocess
import sys

import pytest

from swarmdeck.console.recording.reader import open_recording


def _console(path, **popen) -> subprocess.Popen:
    """A real `swarmdeck console` process (4 robots, no inputs) recording to ``path``; pipes as text."""
    return subprocess.Popen(
        [sys.executable, "-c", "import sys; from swarmdeck.console.cli import main; sys.exit(main())",
         "console", "--port", "0", "--robots", "4", "--no-inputs", "--record", str(path)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **popen)


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_signal_closes_the_recording_cleanly(tmp_path, sig) -> None:
    path = tmp_path / "run.mcap"
    proc = _console(path)
    try:
        for line in proc.stdout:  # the URL line: the loop and the recorder are running
            if "swarmdeck console: http://" in line:
                break
        os.kill(proc.pid, sig)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    assert proc.returncode == 0, err
    assert "stopping (robots stopped)" in err
    with open_recording(path) as r:
        assert r.indexed and not r.warnings, r.warnings  # the summary was written: closed cleanly
        assert r.last_frame is not None and r.last_frame.tick >= 1


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_during_start_up_still_stops_the_robots_and_closes_the_recording(tmp_path, sig) -> None:
    """The signal goes as soon as the recording is open, while the web server and the loop are still starting.
    Before the fix SIGTERM's handler was installed only once the console was up (the default action killed
    the process) and a Ctrl-C there skipped every close: either way the recording was left unclosed (recovered
    by scanning, no summary) and the robots' sink was never told to stop. Wherever in start-up the signal lands,
    the console now stops the robots and closes the recording."""
    path = tmp_path / "run.mcap"
    proc = _console(path, preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))  # as a terminal's Ctrl-C finds it
    try:
        for line in proc.stderr:  # the recorder is open; the app, its server and the loop come next
            if "recording to" in line:
                break
        os.kill(proc.pid, sig)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    assert proc.returncode in (0, 130), (proc.returncode, err)
    assert ("interrupted while starting (robots stopped)" in err) == (proc.returncode == 130), err
    assert "(robots stopped)" in err and "recorded" in err, err
    with open_recording(path) as r:
        assert r.indexed and not r.warnings, r.warnings  # closed cleanly, whenever the signal came
