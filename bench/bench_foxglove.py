"""Foxglove channels benchmarks (issue 19): loop-thread overhead and file size per minute at N = 12 and 100.

Run: ``.venv/bin/python bench/bench_foxglove.py`` (prints markdown tables; ~2 min).

1. Loop-thread overhead: real ControlLoop ticks (coverage + barrier QP) with a Recorder subscribed
   that writes the Foxglove channels vs one that does not (``RecorderConfig(foxglove=False)``),
   alternating short blocks so load drift on the shared machine cancels; the loop thread only
   enqueues in both cases, the Foxglove encoding runs on the writer thread.
2. The writer thread's extra work: ``FoxgloveEncoder.encode`` per frame, process CPU time, and the
   Frame's own JSON encoding (``to_dict`` + msgspec) in the same process as the baseline.
3. File size per minute with and without the Foxglove channels (real loop frames, zstd chunks).
"""
from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

from swarmdeck.console.recording.foxglove import FoxgloveEncoder
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig, encode_json
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.core.constants import CONTROL_PERIOD


def ms(x: float) -> str:
    return f"{x * 1e3:.3f}"


def overhead(tmp: Path, n: int, rounds: int = 10, ticks: int = 4) -> tuple[str, list]:
    loop = ControlLoop(LoopConfig(n_robots=n, seed=2))
    for _ in range(5):
        loop.tick()
    recs = {False: Recorder(tmp / f"off{n}.mcap", config=RecorderConfig(foxglove=False)),
            True: Recorder(tmp / f"on{n}.mcap")}
    times: dict[bool, list[float]] = {False: [], True: []}
    frames = []
    for _ in range(rounds):
        for fox in (False, True):
            unsub = loop.subscribe(recs[fox].write_frame)
            for _ in range(ticks):
                t = time.perf_counter()
                frames.append(loop.tick())
                times[fox].append(time.perf_counter() - t)
            unsub()
    for r in recs.values():
        r.close()
    loop.close()
    off, on = statistics.median(times[False]), statistics.median(times[True])
    return (f"| {n} | {ms(off)} | {ms(on)} | {100 * (on / off - 1):+.1f} % |", frames)


def writer_cost(frames: list) -> tuple[float, float]:
    enc = FoxgloveEncoder(frames[0].bounds)
    t0 = time.process_time()
    for k, f in enumerate(frames):
        for _ in enc.encode(f, k, f.time):
            pass
    fox = (time.process_time() - t0) / len(frames)
    t0 = time.process_time()
    for f in frames:
        encode_json(f.to_dict())
    base = (time.process_time() - t0) / len(frames)
    return fox, base


def size(tmp: Path, frames: list, fox: bool) -> float:
    path = tmp / f"size{fox}{frames[0].n}.mcap"
    with Recorder(path, config=RecorderConfig(foxglove=fox)) as rec:
        for f in frames:
            rec.write_frame(f)
    secs = frames[-1].time - frames[0].time + frames[0].dt
    return path.stat().st_size / secs * 60 / 1e6


def main() -> int:
    print(f"Foxglove channel benchmarks — {time.strftime('%Y-%m-%d')}, {harness.machine()}\n")
    rows_o, rows_w, rows_s = [], [], []
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        for n in (12, 100):
            row, frames = overhead(tmp, n)
            rows_o.append(row)
            fox, base = writer_cost(frames)
            rows_w.append(f"| {n} | {ms(fox)} | {ms(base)} | {fox / base:.1f}x | {100 * fox / CONTROL_PERIOD:.1f} % |")
            seq = []
            loop = ControlLoop(LoopConfig(n_robots=n, seed=1))
            seq = [loop.tick() for _ in range(300 if n == 12 else 150)]
            loop.close()
            off, on = size(tmp, seq, False), size(tmp, seq, True)
            rows_s.append(f"| {n} | {off:.1f} MB | {on:.1f} MB | {on - off:.1f} MB ({100 * (on / off - 1):+.0f} %) |")
    print("### Loop-thread overhead (tick median, recorder subscribed; alternating blocks)\n")
    print("| N | tick, recorder without Foxglove (ms) | tick, recorder with Foxglove (ms) | difference |")
    print("| ---: | ---: | ---: | ---: |")
    print("\n".join(rows_o) + "\n")
    print("### Writer-thread work per frame (process CPU time)\n")
    print("| N | Foxglove channels (ms) | baseline: Frame JSON (ms) | ratio | share of one core at 30 Hz |")
    print("| ---: | ---: | ---: | ---: | ---: |")
    print("\n".join(rows_w) + "\n")
    print("### File size per minute (30 Hz, zstd chunks of 0.25 s)\n")
    print("| N | without Foxglove channels | with | Foxglove's share |")
    print("| ---: | ---: | ---: | ---: |")
    print("\n".join(rows_s))
    return 0


if __name__ == "__main__":
    sys.exit(main())
