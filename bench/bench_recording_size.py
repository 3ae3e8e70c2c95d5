"""Recording MB/min at N = 12, 100, 1000 with and without the Foxglove channels (issue 27 item 5).

Run: ``.venv/bin/python bench/bench_recording_size.py`` (~4 min). Real ControlLoop frames (coverage +
barrier) at 30 Hz, written by the real Recorder (zstd chunks of ``chunk_frames`` = 20 frames unless said); each
configuration recorded 3 times: file MB per minute of recorded time, and the writer's process CPU per
frame, median (worst) of the 3 — beside the same-process baseline (harness.baseline) of the same run.
Rows: Foxglove channels off; on with today's defaults (packed: the robots as one PointCloud; robot_rate 1000: 10
scenes/s at N = 100, 1/s at N = 1000; Voronoi edges and barrier pairs every 1 s; a keyframe every 20 frames); on,
one entity per robot (``FoxgloveConfig.per_entity()``, ``--foxglove-entities``: the default before issue 27 item 5);
and the defaults with the chunks (keyframes) of 8 frames of before, channels off and on.
"""
from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

from swarmdeck.console.recording.foxglove import FoxgloveConfig
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig

# N, ticks recorded, arena bounds (m; N = 1000 does not fit the default 3.2 m x 2 m floor)
SIZES = ((12, 300, None), (100, 150, None), (1000, 60, (-6.0, 6.0, -4.0, 4.0)))
CONFIGS = (("off", RecorderConfig(foxglove=False), None),
           ("on (default: packed, robot_rate 1000, lines_period 1)", RecorderConfig(), FoxgloveConfig()),
           ("on, per entity (--foxglove-entities)", RecorderConfig(), FoxgloveConfig.per_entity()),
           ("off, chunk_frames 8 (before)", RecorderConfig(foxglove=False, chunk_frames=8), None),
           ("on (default), chunk_frames 8 (before)", RecorderConfig(chunk_frames=8), FoxgloveConfig()))


def loop_frames(n: int, ticks: int, bounds: tuple[float, float, float, float] | None) -> list:
    loop = ControlLoop(LoopConfig(n_robots=n, seed=1, **({"bounds": bounds} if bounds else {})))
    frames = [loop.tick() for _ in range(ticks)]
    loop.close()
    return frames


def record(path: Path, frames: list, config: RecorderConfig, fox: FoxgloveConfig | None) -> int:
    with Recorder(path, config=config, foxglove=fox) as rec:
        for f in frames:
            rec.write_frame(f)
    return path.stat().st_size


def main() -> int:
    print(f"recording size — {time.strftime('%Y-%m-%d')}, {harness.machine()}\n")
    base = harness.baseline(clock="cpu")
    print(f"same-process baseline (numpy sort workload, CPU): {base.ms()} ms\n")
    print(harness.table_header(["N", "Foxglove channels", "MB/min", "× off", "writer CPU/frame ms, median (worst)"]))
    with tempfile.TemporaryDirectory() as d:
        for n, ticks, bounds in SIZES:
            frames = loop_frames(n, ticks, bounds)
            minutes = (frames[-1].time - frames[0].time + frames[0].dt) / 60
            off = None
            for name, config, fox in CONFIGS:
                cpu, size = [], 0
                for k in range(3):
                    t, size = harness.timed(record, Path(d) / f"{n}-{k}.mcap", frames, config, fox)
                    cpu.append(t / len(frames))
                mb = size / 1e6 / minutes
                off = off or mb
                print(harness.table_row(n, name, f"{mb:.1f}", f"{mb / off:.1f}", harness.timing(cpu, "cpu")),
                      flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
