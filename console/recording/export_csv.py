"""CSV export of a recording, for pandas / MATLAB users.

Two files in the output folder:

``robots.csv``
    one row per robot per frame (long format): ``t`` recording time s,
    ``time`` loop clock s, ``tick``, ``id``, ``x``, ``y`` m, ``theta`` rad,
    ``v`` m/s, ``w`` rad/s (unicycle command sent), ``nominal_x``,
    ``nominal_y``, ``safe_x``, ``safe_y`` m/s (single-integrator commands of the
    look-ahead point before/after the safety filter), ``seen`` 0/1.
    pandas: ``pd.read_csv("robots.csv").pivot(index="t", columns="id", values="x")``;
    MATLAB: ``T = readtable("robots.csv"); x7 = T.x(T.id == 7)``.
``frames.csv``
    one row per frame: ``t``, ``time``, ``tick``, ``run_time``, ``n``,
    ``run_state``, ``behaviour``, ``barrier_ok``, ``n_active``,
    ``min_distance`` m, ``cost_H``, ``events`` (``" | "``-joined).

Floats are written with 17 significant digits (exact doubles).
"""
from __future__ import annotations

import csv
import os
from pathlib import Path

import numpy as np

from swarmdeck.console.recording.reader import Recording
from swarmdeck.console.runtime.frame import filled

ROBOT_COLUMNS = ("t", "time", "tick", "id", "x", "y", "theta", "v", "w",
                 "nominal_x", "nominal_y", "safe_x", "safe_y", "seen")
FRAME_COLUMNS = ("t", "time", "tick", "run_time", "n", "run_state", "behaviour", "barrier_ok", "n_active",
                 "min_distance", "cost_H", "events")


def export_csv(recording: Recording, out_dir: str | os.PathLike[str], start: float | None = None,
               end: float | None = None) -> tuple[Path, Path, int]:
    """Write ``robots.csv`` and ``frames.csv`` for frames in [start, end) s; returns (paths…, frames written)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    robots_path, frames_path = out / "robots.csv", out / "frames.csv"
    n_frames = 0
    with open(robots_path, "w", newline="", encoding="utf-8") as fr, \
            open(frames_path, "w", newline="", encoding="utf-8") as ff:
        fr.write(",".join(ROBOT_COLUMNS) + "\n")
        fw = csv.writer(ff)
        fw.writerow(FRAME_COLUMNS)
        for t, f in recording.frames(start, end):
            n = f.n
            block = np.column_stack((
                np.full(n, t), np.full(n, f.time), np.full(n, f.tick), f.ids, f.poses, f.v, f.w,
                f.nominal, f.safe, filled(f.seen).astype(float),
            ))
            fmt = ["%.17g", "%.17g", "%d", "%d"] + ["%.17g"] * 9 + ["%d"]
            np.savetxt(fr, block, fmt=fmt, delimiter=",")
            b, c = f.barrier, f.coverage
            fw.writerow([repr(t), repr(f.time), f.tick, repr(f.run_time), n, f.run_state, f.behaviour,
                         "" if b is None else int(b.ok), "" if b is None else b.n_active,
                         "" if b is None else repr(b.min_distance), "" if c is None else repr(c.cost_H),
                         " | ".join(f.events)])
            n_frames += 1
    return robots_path, frames_path, n_frames
