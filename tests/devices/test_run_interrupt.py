"""`swarmdeck run` without --duration: Ctrl-C stops the robots and still prints the report (issue 14,
item 19). A real process and a real SIGINT."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap


def test_ctrl_c_prints_the_report_and_exits_130(tmp_path) -> None:
    script = tmp_path / "forever.py"
    script.write_text(textwrap.dedent("""
        from swarmdeck.devices import Arena

        def experiment(arena: Arena) -> None:
            arena.step()
            print("running", flush=True)
            while True:
                p = arena.positions()
                arena.set_velocities(-(p - p.mean(axis=0)))
                arena.step()
    """))
    proc = subprocess.Popen(
        [sys.executable, "-c", "import sys; from swarmdeck.console.cli import main; sys.exit(main())",
         "run", str(script), "--robots", "4", "--seed", "2", "--json"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        # a test runner's worker may ignore SIGINT, and a child inherits that (Python then installs no
        # Ctrl-C handler): give the child the terminal's default, as a user's shell does
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        assert proc.stdout.readline().strip() == "running"
        os.kill(proc.pid, signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    assert proc.returncode == 130, err
    report = json.loads(out)
    assert report["interrupted"] is True and report["error"] is None
    (arena,) = report["reports"]
    assert arena["n_robots"] == 4 and arena["time"] > 0
    assert "interrupted (robots stopped)" in err
