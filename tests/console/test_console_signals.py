"""SIGTERM and SIGHUP stop `swarmdeck console` like Ctrl-C: robots stopped, the recording closed with
its summary (issue 14, item 14). A real console process, a real signal."""
from __future__ import annotations

import os
import signal
import subprocess
import sys

import pytest

from swarmdeck.console.recording.reader import open_recording


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_signal_closes_the_recording_cleanly(tmp_path, sig) -> None:
    path = tmp_path / "run.mcap"
    proc = subprocess.Popen(
        [sys.executable, "-c", "import sys; from swarmdeck.console.cli import main; sys.exit(main())",
         "console", "--port", "0", "--robots", "4", "--no-inputs", "--record", str(path)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
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
