"""Compact recordings (issue 18 item 4): file size per minute and writer CPU, format 2 vs format 1.

Run: ``.venv/bin/python bench/bench_recording_compact.py`` (a few minutes; N = 1000 ticks are slow).

Frames of real console loops (``ControlLoop``: coverage on the moving density, the barrier —
distributed above 200 robots —, wheel limits) at N = 12, 100 (3.2 × 2 m arena) and 1000
(10 × 6 m). Each run is recorded by the real ``Recorder`` (zstd chunks closed every 0.25 s of
recorded time). *Format 1* is the same frames as ``Frame.to_dict()`` JSON through the same
chunking and compression (the baseline, in the same process). Each N is recorded with and
without the Foxglove channels (``RecorderConfig.foxglove``, on by default), and the size per
minute is the growth per frame (between an 8-frame and the full recording) × 30 × 60. *Writer CPU* is the process CPU
time of the writer thread's work per frame (encode, compress, write), as a share of one core at
30 frames per second.
"""
from __future__ import annotations

import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import zstandard

from swarmdeck.console.recording.codec import encode_frame, encode_json
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig


def loop_frames(n: int, ticks: int) -> list:
    bounds = (-1.6, 1.6, -1.0, 1.0) if n <= 100 else (-5.0, 5.0, -3.0, 3.0)
    loop = ControlLoop(LoopConfig(n_robots=n, seed=1, bounds=bounds))
    try:
        return [loop.tick() for _ in range(ticks)]
    finally:
        loop.close()


def format1_bytes(frames: list) -> int:
    """Format 1 through the same 0.25 s zstd chunks (8 frames at 30 Hz)."""
    return sum(len(zstandard.compress(b"".join(encode_json(f.to_dict()) for f in frames[i:i + 8])))
               for i in range(0, len(frames), 8))


def main() -> int:
    cpu = next((ln.split(":", 1)[1].strip() for ln in open("/proc/cpuinfo") if ln.startswith("model name")), "?")
    print(f"# bench_recording_compact  {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}  nproc={os.cpu_count()}  "
          f"cpu={cpu}  python={sys.version.split()[0]}  load={os.getloadavg()[0]:.1f}\n")
    print("| N | frames | Foxglove channels | format 2 MB/min (30 Hz) | format 1 MB/min | ratio | kB/frame | "
          "writer CPU ms/frame | writer % of a core at 30 Hz | encode ms/frame |")
    print("| ---: | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    with tempfile.TemporaryDirectory() as d:
        for n, ticks in ((12, 240), (100, 120), (1000, 40)):
            frames = loop_frames(n, ticks)
            enc = []
            for f in frames[: min(len(frames), 30)]:
                t = time.process_time()
                encode_frame(f)
                enc.append(time.process_time() - t)
            seconds = len(frames) * frames[0].dt
            old = format1_bytes(frames) / seconds * 60 / 1e6
            for foxglove in (False, True):
                sizes, writer = [], 0.0
                for k in (8, len(frames)):  # the growth per frame: header, schemas, summary written once
                    path = Path(d) / f"n{n}_{k}_{foxglove}.mcap"
                    c0 = time.process_time()
                    with Recorder(path, config=RecorderConfig(foxglove=foxglove)) as rec:
                        for f in frames[:k]:
                            rec.write_frame(f)
                    writer = (time.process_time() - c0) / k
                    sizes.append(path.stat().st_size)
                per_frame = (sizes[1] - sizes[0]) / (len(frames) - 8)
                per_min = per_frame * 30 * 60 / 1e6
                print(f"| {n} | {len(frames)} | {'on' if foxglove else 'off'} | {per_min:.1f} | {old:.1f} | "
                      f"{old / per_min:.1f} | {per_frame / 1e3:.1f} | {1e3 * writer:.2f} | "
                      f"{100 * writer / 0.033:.0f} % | {1e3 * statistics.median(enc):.2f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
