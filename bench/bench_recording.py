"""Recording benchmarks (issue 8): loop-thread overhead, file size per minute, seek in a one-hour file.

Run: ``.venv/bin/python bench/bench_recording.py`` (prints markdown tables; ~3 min, ~300 MB in a temp dir).

1. Overhead per tick on the loop thread at N = 100: the real ControlLoop ticks with the
   recorder subscribed (enqueue only) vs without, interleaved blocks; and the cost of the
   enqueue call itself vs serialising inline (``to_dict`` + msgspec JSON + MCAP, what the writer
   thread does) — the baseline a synchronous recorder would pay on the loop thread.
2. File size per minute at N = 12 and N = 100 (real loop frames, zstd chunks of 0.25 s).
3. Seek to the middle of a one-hour file (N = 12, 30 Hz, synthetic: real frames re-timed):
   open (summary index) + ``frame_at(duration / 2)`` with a cold cache, vs the same file
   without its summary (what a crash leaves: the reader scans the chunk headers).
"""
from __future__ import annotations

import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder, encode_json
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.core.constants import CONTROL_PERIOD

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the synthetic-session fixture
from recording_synth import retimed  # noqa: E402


def ms(x: float) -> str:
    return f"{x * 1e3:.3f}"


def loop_frames(n: int, ticks: int, seed: int = 1) -> list:
    loop = ControlLoop(LoopConfig(n_robots=n, seed=seed))
    frames = [loop.tick() for _ in range(ticks)]
    loop.close()
    return frames


def overhead(tmp: Path, n: int = 100, rounds: int = 12, ticks: int = 4) -> list[str]:
    loop = ControlLoop(LoopConfig(n_robots=n, seed=2))
    for _ in range(5):
        loop.tick()
    rec = Recorder(tmp / "overhead.mcap")
    enqueue: list[float] = []

    def timed(frame) -> None:
        t = time.perf_counter()
        rec.write_frame(frame)
        enqueue.append(time.perf_counter() - t)

    with_rec: list[float] = []
    without: list[float] = []
    frames = []
    for _ in range(rounds):  # short alternating blocks, so load drift on a shared machine cancels
        for target, subscribe in ((without, False), (with_rec, True)):
            unsub = loop.subscribe(timed) if subscribe else None
            for _ in range(ticks):
                t = time.perf_counter()
                frames.append(loop.tick())
                target.append(time.perf_counter() - t)
            if unsub is not None:
                unsub()
    st = rec.close()
    loop.close()
    # the writer thread's work per frame, measured as process CPU time of recording alone
    rec2 = Recorder(tmp / "cpu.mcap")
    c0 = time.process_time()
    for f in frames:
        rec2.write_frame(f)
    rec2.close()
    cpu = (time.process_time() - c0) / len(frames)
    # the inline baseline: that work done synchronously on the loop thread
    from mcap.writer import Writer

    with open(tmp / "inline.mcap", "wb") as fh:
        w = Writer(fh)
        w.start("swarmdeck", "bench")
        ch = w.register_channel("/f", "json", w.register_schema("f", "jsonschema", b"{}"))
        inline = []
        for k, frame in enumerate(frames):
            t = time.perf_counter()
            w.add_message(ch, log_time=k, data=encode_json(frame.to_dict()), publish_time=k)
            inline.append(time.perf_counter() - t)
        w.finish()
    e_med, e_p99 = statistics.median(enqueue), float(np.percentile(enqueue, 99))
    i_med = statistics.median(inline)
    t_with, t_without = statistics.median(with_rec), statistics.median(without)
    return [
        f"### Loop-thread overhead, N = {n} (real ControlLoop ticks: coverage + barrier QP)",
        "",
        "| measure | median (ms) | note |",
        "| --- | ---: | --- |",
        f"| `write_frame` (enqueue) on the loop thread | {ms(e_med)} | p99 {ms(e_p99)} ms; {st.dropped} dropped |",
        f"| inline baseline: to_dict + JSON + MCAP add on the loop thread | {ms(i_med)} | {i_med / e_med:.0f}x the enqueue |",
        f"| writer thread CPU per frame (JSON, zstd, write) | {ms(cpu)} | {100 * cpu / CONTROL_PERIOD:.0f} % of one core at 30 Hz |",
        f"| tick without recorder | {ms(t_without)} | {rounds}×{ticks} ticks, alternating blocks |",
        f"| tick with recorder (writer thread running) | {ms(t_with)} | {100 * (t_with / t_without - 1):+.1f} % |",
    ]


def size_per_minute(tmp: Path) -> list[str]:
    rows = ["### File size per minute (30 Hz frames, zstd, 0.25 s chunks)", "",
            "| N | recorded | file | per minute | JSON per frame (uncompressed) |", "| ---: | ---: | ---: | ---: | ---: |"]
    for n, ticks in ((12, 300), (100, 150)):
        frames = loop_frames(n, ticks)
        path = tmp / f"size{n}.mcap"
        with Recorder(path) as rec:
            for f in frames:
                rec.write_frame(f)
        secs = frames[-1].time - frames[0].time + frames[0].dt
        size = path.stat().st_size
        raw = statistics.median(len(json.dumps(f.to_dict())) for f in frames[::10])
        rows.append(f"| {n} | {secs:.1f} s | {size / 1e6:.2f} MB | {size / secs * 60 / 1e6:.1f} MB | {raw / 1e3:.1f} kB |")
    return rows


def seek_one_hour(tmp: Path, n: int = 12, hours: float = 1.0, dt: float = CONTROL_PERIOD) -> list[str]:
    base = loop_frames(n, 60)
    path = tmp / "hour.mcap"
    total = int(hours * 3600 / dt)
    t0 = time.perf_counter()
    rec = Recorder(path)
    for k in range(total):
        while rec.status().queued > 2000:  # a generator faster than any loop: wait for the writer
            time.sleep(0.005)
        rec.write_frame(retimed(base[k % len(base)], k, k * dt))
    rec.close()
    t_write = time.perf_counter() - t0
    size = path.stat().st_size

    def cold_seek(p: Path, where: float) -> tuple[float, float, int]:
        t = time.perf_counter()
        r = open_recording(p)
        t_open = time.perf_counter() - t
        t = time.perf_counter()
        _, f = r.frame_at(where)
        t_seek = time.perf_counter() - t
        r.close()
        return t_open, t_seek, f.tick

    mid = (total - 1) * dt / 2
    opens, seeks = [], []
    for i in range(5):
        o, s, tick = cold_seek(path, mid + i * 7.3)
        opens.append(o)
        seeks.append(s)
    with open_recording(path) as r:  # warm reader, cold chunks: seeks across the file
        warm = []
        for i in range(20):
            t = time.perf_counter()
            r.frame_at((i + 0.5) * r.duration / 20)
            warm.append(time.perf_counter() - t)
        n_chunks = r.n_chunks
    # the file a crash leaves: no summary → the reader scans chunk headers first
    data_end = tmp / "hour_nosummary.mcap"
    raw = path.read_bytes()
    summary_start = int.from_bytes(raw[len(raw) - 28: len(raw) - 20], "little")
    data_end.write_bytes(raw[: summary_start - 13])
    del raw
    o2, s2, _ = cold_seek(data_end, mid)
    return [
        f"### Seek to the middle of a one-hour file (N = {n}, {1 / dt:.0f} Hz, {total} frames, "
        f"{size / 1e6:.0f} MB, {n_chunks} chunks; written in {t_write:.0f} s)",
        "",
        "| operation | median (ms) |",
        "| --- | ---: |",
        f"| open (MCAP summary → chunk index) | {ms(statistics.median(opens))} |",
        f"| seek to the middle, cold chunk cache | {ms(statistics.median(seeks))} |",
        f"| seek anywhere (20 positions), open reader | {ms(statistics.median(warm))} |",
        f"| open + seek without summary (crashed file: header scan) | {ms(o2 + s2)} "
        f"({(o2 + s2) / (statistics.median(opens) + statistics.median(seeks)):.2f}x the indexed open + seek) |",
    ]


def main() -> int:
    print(f"recording benchmarks — {time.strftime('%Y-%m-%d')}, {harness.machine()}\n")
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        for section in (overhead(tmp), size_per_minute(tmp), seek_one_hour(tmp)):
            print("\n".join(section) + "\n", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
