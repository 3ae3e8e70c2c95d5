"""Crash safety: a recording process killed with SIGKILL leaves a file that plays all but its last second."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

from swarmdeck.console.recording.reader import open_recording

CHILD = textwrap.dedent("""
    import sys, time
    from swarmdeck.console.recording.recorder import Recorder
    from recording_synth import retimed, simulated_frames

    frames = list(simulated_frames(n_robots=20, n_ticks=50, dt=0.02, coverage=False))
    rec = Recorder(sys.argv[1], {"config": {"child": True}})
    k = 0
    next_t = time.monotonic()
    while True:                               # a 50 Hz loop that records every tick, until killed
        now = time.monotonic()
        rec.write_frame(retimed(frames[k % len(frames)], k, now))
        rec.write_datagram(b"ping", ("127.0.0.1", 9), "udp", now)
        print(k, repr(now), flush=True)
        k += 1
        next_t += 0.02
        time.sleep(max(0.0, next_t - time.monotonic()))
""")


def test_kill_9_loses_at_most_the_last_second(tmp_path):
    path = tmp_path / "crash.mcap"
    env = {**os.environ, "PYTHONPATH": os.path.dirname(os.path.dirname(os.path.abspath(__file__)))}  # recording_synth lives beside this file
    proc = subprocess.Popen([sys.executable, "-c", CHILD, str(path)], stdout=subprocess.PIPE, text=True, env=env)
    written = []
    try:
        for line in proc.stdout:
            k, t = line.split()
            written.append(float(t))
            if int(k) >= 75:  # 1.5 s of recording, several chunk flushes
                break
        t_kill = time.monotonic()
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(10)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    assert proc.returncode == -signal.SIGKILL
    with open_recording(path) as r:
        assert not r.indexed and r.warnings  # no summary: recovered by scanning
        ticks = [f.tick for _, f in r.frames()]
        assert ticks == list(range(len(ticks))), "the recovered frames are the run's first ticks, in order"
        last_time = r.last_frame.time
        # every frame enqueued more than one second before the kill is in the file
        assert last_time >= t_kill - 1.0, f"lost {t_kill - last_time:.2f} s"
        print(f"lost the last {t_kill - last_time:.3f} s")
        assert sum(1 for t in written if t <= t_kill - 1.0) <= len(ticks)
        assert r.config()["config"] == {"child": True}
        assert sum(1 for _ in r.datagrams()) >= len(ticks) - 1
