"""A disk that stalls: the loop never blocks, the oldest queued items are dropped, counted and reported."""
from __future__ import annotations

import threading

from recording_synth import retimed, simulated_frames

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig


class StallingFile:
    """A real file whose writes block while ``gate`` is closed (a disk that stops answering)."""

    def __init__(self, path):
        self.f = open(path, "wb")
        self.gate = threading.Event()
        self.gate.set()

    def write(self, data):
        self.gate.wait()
        return self.f.write(data)

    def flush(self):
        self.gate.wait()
        self.f.flush()

    def tell(self):
        return self.f.tell()

    def close(self):
        self.f.close()


def test_a_stalled_disk_drops_oldest_and_says_so(tmp_path):
    files = []
    path = tmp_path / "stalled.mcap"
    rec = Recorder(path, config=RecorderConfig(queue_size=16),
                   opener=lambda p: files.append(StallingFile(p)) or files[-1])
    files[0].gate.clear()  # the disk stalls
    base = list(simulated_frames(n_robots=10, n_ticks=5, coverage=False))
    written = 0
    for k in range(100_000):  # the loop goes on and never blocks on the recorder
        assert rec.write_frame(retimed(base[k % 5], k, k * 0.033))
        written += 1
        if rec.status().dropped >= 50:
            break
    st = rec.status()
    assert st.dropped >= 50 and st.queued <= 16 and st.state == "recording" and "dropped" in st.message
    files[0].gate.set()  # the disk answers again
    final = rec.close()
    assert final.state == "closed" and final.frames + final.dropped == written
    with open_recording(path) as r:
        ticks = [f.tick for _, f in r.frames()]
        assert len(ticks) == final.frames and ticks == sorted(ticks) and ticks[-1] == written - 1
        assert len(ticks) < written  # the gap is where the oldest were dropped
        notes = [e.text for e in r.events() if e.kind == "recorder"]
        assert notes and sum(int(n.split(": ")[1].split()[0]) for n in notes) == final.dropped
