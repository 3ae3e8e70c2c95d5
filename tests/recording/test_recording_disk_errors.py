"""An unwritable path or a full disk: a clear message, recording disabled, and the run goes on."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap

from recording_synth import simulated_frames

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder


def test_unwritable_path_disables_recording_with_a_message(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("a file where a folder should be")
    rec = Recorder(blocker / "sessions" / "x.mcap")
    st = rec.status()
    assert st.state == "disabled" and not st.ok
    assert "cannot write" in st.message and str(blocker) in st.message
    frame = next(simulated_frames(n_robots=2, n_ticks=1, coverage=False))
    assert rec.write_frame(frame) is False  # no exception into the loop
    assert rec.write_datagram(b"x", ("h", 1), "udp", 0.0) is False
    assert rec.close().state == "disabled"


def test_a_device_that_is_full_from_the_start(tmp_path):
    rec = Recorder("/dev/full")
    st = rec.status()
    assert st.state == "disabled" and "No space left on device" in st.message
    rec.close()


CHILD = textwrap.dedent("""
    import json, resource, signal, sys
    from swarmdeck.console.recording.recorder import Recorder
    from recording_synth import retimed, simulated_frames

    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)           # writes past the limit fail with EFBIG instead
    resource.setrlimit(resource.RLIMIT_FSIZE, (150_000, 150_000))  # a disk that fills up after ~150 kB
    base = list(simulated_frames(n_robots=30, n_ticks=10, coverage=False))
    rec = Recorder(sys.argv[1])
    ticks = 0
    for k in range(4000):                                   # the loop keeps ticking whatever happens
        rec.write_frame(retimed(base[k % 10], k, k * 0.033))
        ticks += 1
        if rec.status().state == "failed":
            break
        if k % 50 == 49:
            import time; time.sleep(0.3)                     # let the writer reach the limit
    st = rec.close()
    print(json.dumps({"ticks": ticks, "state": st.state, "message": st.message,
                      "accepted_after": rec.write_frame(base[0])}))
""")


def test_disk_full_mid_run_stops_recording_and_the_loop_goes_on(tmp_path):
    path = tmp_path / "full.mcap"
    env = {**os.environ, "PYTHONPATH": os.path.dirname(os.path.dirname(os.path.abspath(__file__)))}  # recording_synth lives beside this file
    out = subprocess.run([sys.executable, "-c", CHILD, str(path)], capture_output=True, text=True, timeout=60, env=env)
    assert out.returncode == 0, out.stderr
    res = json.loads(out.stdout.strip().splitlines()[-1])
    assert res["state"] == "failed" and "File too large" in res["message"] and "the run goes on" in res["message"]
    assert res["accepted_after"] is False
    with open_recording(path) as r:  # what was written before the disk filled still plays
        ticks = [f.tick for _, f in r.frames()]
        assert ticks and ticks == list(range(len(ticks)))
