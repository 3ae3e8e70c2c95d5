"""Compact recordings (issue 18 item 4): file size per minute and writer CPU, format 3 vs format 2.

Run: ``.venv/bin/python bench/bench_recording_compact.py`` (a few minutes).

Frames of real console loops (``ControlLoop``: coverage on the moving density, the barrier —
distributed above 200 robots —, wheel limits, simulated robots) at N = 12, 100 (3.2 × 2 m arena)
and 1000 (10 × 6 m). Each run is recorded by the real ``Recorder`` (zstd chunks closed every
0.25 s of recorded time: 8 frames at 30 Hz), in frame format 3 (a keyframe first in every chunk,
the others predicted from the frame before) and — the baseline, same process, same frames, same
recorder — with every frame self-contained (format 2's layout: the recorder is told it has no
previous frame). *Tracked* rows: the same frames with a tracker's noise on the poses (Gaussian,
1 mm and 5 mrad: the poses no longer follow the commands, as measured poses do not). Without the
Foxglove channels (``RecorderConfig(foxglove=False)``: swarmdeck's own channels; the Foxglove
channels come on top: last column, simulated rows). Size per minute = the growth per frame (between an 8-frame
and the full recording: header, schemas, summary written once) × 30 × 60. *Writer CPU* = process
CPU time of recording the frames (encode, zstd, write) per frame, as a share of one core at 30 Hz;
*encode* = ``encode_frame`` alone (median; format 3: a predicted frame).
"""
from __future__ import annotations

import dataclasses
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from swarmdeck.console.recording.codec import encode_frame
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.devices.gritsbot import wrap_angle


class SelfContainedRecorder(Recorder):
    """The recorder writing every frame as a keyframe (format 2's bytes): the baseline."""

    @property
    def _previous(self):  # noqa: D102 - never a previous frame to predict from
        return None

    @_previous.setter
    def _previous(self, frame) -> None:
        pass


def loop_frames(n: int, ticks: int) -> list:
    bounds = (-1.6, 1.6, -1.0, 1.0) if n <= 100 else (-5.0, 5.0, -3.0, 3.0)
    loop = ControlLoop(LoopConfig(n_robots=n, seed=1, bounds=bounds))
    try:
        return [loop.tick() for _ in range(ticks)]
    finally:
        loop.close()


def tracked(frames: list, seed: int = 0) -> list:
    rng = np.random.default_rng(seed)
    out = []
    for f in frames:
        p = f.poses + rng.normal(0.0, [0.001, 0.001, 0.005], f.poses.shape)
        p[:, 2] = wrap_angle(p[:, 2])
        out.append(dataclasses.replace(f, poses=p))
    return out


def growth(d: str, frames: list, recorder: type[Recorder], foxglove: bool = False) -> tuple[float, float]:
    """(bytes per frame, writer CPU s per frame) of recording ``frames``."""
    sizes, cpu = [], 0.0
    for k in (8, len(frames)):
        path = Path(d) / f"{recorder.__name__}_{k}.mcap"
        c0 = time.process_time()
        with recorder(path, config=RecorderConfig(foxglove=foxglove)) as rec:
            for f in frames[:k]:
                rec.write_frame(f)
        cpu = (time.process_time() - c0) / k
        sizes.append(path.stat().st_size)
        path.unlink()
    return (sizes[1] - sizes[0]) / (len(frames) - 8), cpu


def main() -> int:
    cpu = next((ln.split(":", 1)[1].strip() for ln in open("/proc/cpuinfo") if ln.startswith("model name")), "?")
    print(f"# bench_recording_compact  {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}  nproc={os.cpu_count()}  "
          f"cpu={cpu}  python={sys.version.split()[0]}  load={os.getloadavg()[0]:.1f}\n")
    print("| N | poses | frames | format 3 MB/min (30 Hz) | format 2 MB/min | format 3 / format 2 | kB/frame | "
          "writer CPU ms/frame (3 / 2) | writer % of a core at 30 Hz | encode ms/frame (3 / 2) | "
          "format 3 with the Foxglove channels: MB/min, writer % of a core |")
    print("| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    with tempfile.TemporaryDirectory() as d:
        for n, ticks in ((12, 240), (100, 120), (1000, 120)):
            sim = loop_frames(n, ticks)
            for kind, frames in (("simulated", sim), ("tracked", tracked(sim))):
                enc3, enc2 = [], []
                for a, b in zip(frames[:31], frames[1:31]):
                    t = time.process_time()
                    encode_frame(b, a)
                    enc3.append(time.process_time() - t)
                    t = time.process_time()
                    encode_frame(b)
                    enc2.append(time.process_time() - t)
                f3, cpu3 = growth(d, frames, Recorder)
                f2, cpu2 = growth(d, frames, SelfContainedRecorder)
                mb3, mb2 = f3 * 1800 / 1e6, f2 * 1800 / 1e6
                fox = "—"
                if kind == "simulated":
                    ff, cpuf = growth(d, frames, Recorder, foxglove=True)
                    fox = f"{ff * 1800 / 1e6:.1f}, {100 * cpuf * 30:.0f} %"
                print(f"| {n} | {kind} | {len(frames)} | {mb3:.1f} | {mb2:.1f} | {mb3 / mb2:.2f} | {f3 / 1e3:.1f} | "
                      f"{1e3 * cpu3:.2f} / {1e3 * cpu2:.2f} | {100 * cpu3 * 30:.0f} % | "
                      f"{1e3 * statistics.median(enc3):.2f} / {1e3 * statistics.median(enc2):.2f} | {fox} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
