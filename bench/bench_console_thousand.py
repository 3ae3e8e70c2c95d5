"""The console at scale (issue 18 item 3): tick, scene and recorder cost at N = 100, 500, 1000.

Run: ``.venv/bin/python bench/bench_console_thousand.py`` (a few minutes).

Real ``ControlLoop`` ticks (simulated robots, coverage on the moving density, the barrier in
"auto" mode: distributed above 200 robots) on arenas that hold N at the console's layout spacing
(3.2 × 2, 8 × 5, 10 × 6 m). Per tick, medians over the measured ticks: *tick* = ``loop.tick()``,
*scene* = ``ArenaScene.draw`` of that frame into a viser server (what the viewer thread does),
*record* = the recorder's writer-thread CPU per frame (``Recorder`` with its defaults, the
Foxglove channels included, writing the same frames afterwards). CPU = process CPU time
(robust to the other jobs on this shared 2-core VM), wall = elapsed time. *Loop budget* = tick +
scene + record CPU: all three share the GIL, so ticks/s ≥ 1 / budget on an idle core.
Baseline in the same run: the same loop with the centralised barrier (``mode="centralised"``),
the console's only filter before this issue.
"""
from __future__ import annotations

import statistics  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

from swarmdeck.console.recording.recorder import Recorder  # noqa: E402
from swarmdeck.console.runtime.config import arena_bounds  # noqa: E402
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig, SafetyParams  # noqa: E402
from swarmdeck.console.web.scene import ArenaScene  # noqa: E402

ARENAS = {100: "3.2x2", 500: "8x5", 1000: "10x6"}


def measure(n: int, mode: str, ticks: int, with_scene: bool) -> dict:
    import viser

    cfg = LoopConfig(n_robots=n, seed=1, bounds=arena_bounds(ARENAS[n]), safety=SafetyParams(mode=mode))
    loop = ControlLoop(cfg)
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False) if with_scene else None
    scene = ArenaScene(server, cfg.bounds) if with_scene else None
    out = {k: [] for k in ("tick_cpu", "tick_wall", "scene_cpu", "rec_cpu", "safety_cpu")}
    frames = []
    try:
        for k in range(ticks):
            c, t = time.process_time(), time.perf_counter()
            frame = loop.tick()
            tick_cpu, tick_wall = time.process_time() - c, time.perf_counter() - t
            if k < 3:  # warm-up: first layout, first scene build
                if scene is not None:
                    scene.draw(frame)
                continue
            out["tick_cpu"].append(tick_cpu)
            out["tick_wall"].append(tick_wall)
            out["safety_cpu"].append(frame.timing.get("safety", float("nan")))
            if scene is not None:
                c = time.process_time()
                scene.draw(frame)
                out["scene_cpu"].append(time.process_time() - c)
            frames.append(frame)
            assert frame.barrier.ok, frame.barrier.status
        # the recorder's writer-thread work for these frames (default RecorderConfig: Foxglove channels on)
        with tempfile.TemporaryDirectory() as d:
            c = time.process_time()
            with Recorder(Path(d) / "r.mcap") as rec:
                for f in frames:
                    rec.write_frame(f)
            out["rec_cpu"].append((time.process_time() - c) / len(frames))
    finally:
        loop.close()
        if server is not None:
            server.stop()
    return {k: statistics.median(v) if v else float("nan") for k, v in out.items()}


def main() -> int:
    print(f"# bench_console_thousand  {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}  {harness.machine()}\n")
    print("| N | arena (m) | barrier | tick CPU ms | tick wall ms | scene CPU ms | record CPU ms | "
          "loop budget ms | ticks/s (1 / budget) |")
    print("| ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for n, ticks in ((100, 23), (500, 13), (1000, 13)):
        for mode in ("auto", "centralised"):
            r = measure(n, mode, ticks if mode == "auto" else 8, with_scene=mode == "auto")
            budget = r["tick_cpu"] + (0 if r["scene_cpu"] != r["scene_cpu"] else r["scene_cpu"]) + r["rec_cpu"]
            label = "auto (distributed)" if mode == "auto" and n > 200 else mode
            scene = "—" if r["scene_cpu"] != r["scene_cpu"] else f"{1e3 * r['scene_cpu']:.1f}"
            print(f"| {n} | {ARENAS[n].replace('x', ' × ')} | {label} | {1e3 * r['tick_cpu']:.1f} | "
                  f"{1e3 * r['tick_wall']:.1f} | {scene} | {1e3 * r['rec_cpu']:.1f} | {1e3 * budget:.1f} | "
                  f"{1 / budget:.1f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
