"""Several recordings in one player (issue 31 item 4): frame build time per tick, 3 recordings vs 1.

Run: ``.venv/bin/python bench/bench_compare_play.py`` (about a minute).

Three recordings of real console loops (``ControlLoop``: coverage on the moving density, the barrier, 100
simulated robots, seeds 1–3, 10 s each at 30 Hz), recorded by the real ``Recorder``. The player
(:class:`~swarmdeck.console.web.player.PlayerApp`, a real viser server on loopback, no browser connected: every
update is still built and serialised) plays them at 1× on a virtual clock, one update per 30 Hz tick from 0.5 s
on: *frame build* = what one tick costs the playback thread — ``Player.update`` (each run's frame at its time:
chunk seek and decode) and ``PlayerApp.refresh`` (the scene of run A, the ghosts or the side scenes of the
others, the plots) — on the thread's CPU clock (robust to the other processes of a shared machine), median and
worst case over the ticks. *timeline only*: ``Player.update`` alone (no drawing).
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.web.player import Player, PlayerApp

N, SECONDS, DT = 100, 10.0, 1 / 30
TICKS = 240  # 8 s of playback


def record(path: Path, seed: int) -> None:
    loop = ControlLoop(LoopConfig(n_robots=N, seed=seed, dt=DT))
    try:
        with Recorder(path) as rec:
            for _ in range(int(SECONDS / DT)):
                rec.write_frame(loop.tick())
    finally:
        loop.close()


def per_tick(recs: list, layout: str | None) -> harness.Timing:
    """Thread-CPU time of one playback tick (update + refresh; ``layout`` None: the timeline alone)."""
    clock = harness.CLOCKS["thread"]
    runs = recs if len(recs) > 1 else recs[0]
    app = None if layout is None else PlayerApp(runs, port=0, layout=layout)
    player = Player(runs) if app is None else app.player
    samples = []
    try:
        player.seek(0.5)
        player.play()
        player.update(0.0)
        for k in range(1, TICKS + 1):
            t0 = clock()
            if player.update(k * DT) and app is not None:
                app.refresh()
            samples.append(clock() - t0)
    finally:
        if app is not None:
            app.close()
    return harness.timing(samples, "thread")


def main() -> int:
    print(harness.machine())
    base = harness.baseline()
    print(f"baseline (sort 1e5 ×10): {base.ms()} ms")
    with tempfile.TemporaryDirectory() as d:
        paths = [Path(d) / f"run{s}.mcap" for s in (1, 2, 3)]
        for s, p in zip((1, 2, 3), paths):
            record(p, s)
        recs = [open_recording(p) for p in paths]
        try:
            print(harness.table_header(["recordings", "layout", "frame build per tick (ms)", "timeline only (ms)"]))
            one_t = per_tick(recs[:1], None)
            one = per_tick(recs[:1], "overlay")
            print(harness.table_row("1", "—", one, one_t))
            three_t = per_tick(recs, None)
            for layout in ("overlay", "side"):
                three = per_tick(recs, layout)
                print(harness.table_row("3", layout, three, three_t))
                print(f"  3 vs 1 ({layout}): {three.median / one.median:.2f}× the median")
        finally:
            for r in recs:
                r.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
