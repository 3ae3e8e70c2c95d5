"""Video export speed (issue 16): video frames written per second by ``export_video`` at N = 12 and 100.

Run: ``.venv/bin/python bench/bench_video.py`` (prints a markdown table; ~1–2 min).

For each N a 10 s coverage session at 30 Hz is recorded from the console's real loop
(``tests/recording_synth.py``), then exported three times at 1280×720, 30 fps (300 video
frames, one per recorded frame): the whole export (read + draw + H.264 encode + mux) and the
drawing alone (``FrameRenderer.render`` over the same frames). Baseline in the same process:
reading and decoding those frames with the recording reader (what every exporter pays).
Medians of the three rounds; wall and process CPU time (the machine is shared).
"""
from __future__ import annotations

import os
import statistics
import sys
import tempfile
from pathlib import Path

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

from swarmdeck.console.recording.export_video import FrameRenderer, VideoLayout, VideoStyle, export_video
from swarmdeck.console.recording.reader import open_recording

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))  # the synthetic-session fixture
from recording_synth import write_synthetic_session  # noqa: E402


def timed(fn) -> tuple[float, float]:
    """(wall s, process CPU s) of one call."""
    cpu, (wall, _) = harness.timed(lambda: harness.timed(fn, clock="wall"), clock="cpu")
    return wall, cpu


def bench(n: int, tmp: Path, rounds: int = 3) -> str:
    path = tmp / f"n{n}.mcap"
    write_synthetic_session(path, n_robots=n, seconds=10.0, dt=1 / 30)
    style = VideoStyle()
    read, draw, export = [], [], []
    size = 0
    for k in range(rounds):
        with open_recording(path) as rec:
            read.append(timed(lambda: sum(1 for _ in rec.frames())))
        with open_recording(path) as rec:
            loaded = [f for _, f in rec.frames()]
            r = FrameRenderer(VideoLayout.fit(loaded[0].bounds, style.width, style.height), style)
            draw.append(timed(lambda: [r.render(f, 0.0) for f in loaded]))  # noqa: B023  (timed at once)
        with open_recording(path) as rec:
            out = tmp / f"n{n}-{k}.mp4"
            made: list[int] = []
            export.append(timed(lambda: made.append(export_video(rec, out, style)[1])))  # noqa: B023  (timed at once)
            size = os.path.getsize(out)
    vf = made[0]
    med = lambda xs, i: statistics.median(x[i] for x in xs)  # noqa: E731
    fps = lambda xs, i: vf / med(xs, i)  # noqa: E731
    return (f"| {n} | {vf} | {fps(export, 0):.0f} / {fps(export, 1):.0f} | {fps(draw, 0):.0f} / {fps(draw, 1):.0f} | "
            f"{fps(read, 0):.0f} / {fps(read, 1):.0f} | {med(export, 1) / med(read, 1):.1f} | "
            f"{vf / 30 / med(export, 0):.1f}x | {size / 1e6:.1f} |")


def main() -> None:
    print(harness.machine())
    print("| N | video frames | export frames/s, wall / CPU | drawing alone frames/s, wall / CPU | "
          "baseline: reading frames/s, wall / CPU | export / reading CPU time | real-time factor (wall) | MP4 MB |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    with tempfile.TemporaryDirectory() as d:
        for n in (12, 100):
            print(bench(n, Path(d)), flush=True)


if __name__ == "__main__":
    main()
