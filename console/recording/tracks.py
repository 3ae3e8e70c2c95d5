"""The robots' poses of a recording sampled on a regular grid: what a light viewer overlays (the portal's job
comparison draws two runs' tracks on one canvas, issue 31 item 4).

:func:`sampled_poses` reads the recording's frames once and keeps, at every grid time ``k × period`` s
(recording time), the last frame at or before it: poses (N, 3) — x, y in m, θ in rad — rounded to 1 mm /
1 mrad. At most ``max_samples`` samples: a longer recording is sampled more coarsely (the period is
stretched), so the answer stays small whatever the run's length.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.recording.reader import Recording

DEFAULT_PERIOD = 0.1  # s between samples
MAX_SAMPLES = 1200


@dataclass(frozen=True)
class Tracks:
    """``times`` (T,) recording time s; ``poses`` T arrays (N_k, 3) (N may change within a run); ``ids`` the
    robot ids of the first sample; ``bounds`` the arena (x_min, x_max, y_min, y_max) m; ``period`` s."""

    times: tuple[float, ...]
    poses: tuple[NDArray[np.float64], ...]
    ids: tuple[int, ...]
    bounds: tuple[float, float, float, float]
    period: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: {period, t, ids, bounds, poses: [[[x, y, θ], …], …]}."""
        return {"period": self.period, "t": [round(t, 3) for t in self.times], "ids": list(self.ids),
                "bounds": list(self.bounds), "poses": [np.round(p, 3).tolist() for p in self.poses]}


def sampled_poses(recording: Recording, period: float = DEFAULT_PERIOD, max_samples: int = MAX_SAMPLES) -> Tracks:
    """The poses of ``recording`` every ``period`` s (stretched to keep ≤ ``max_samples``); ValueError for a
    recording with no readable frame or a period that is not a positive number of seconds."""
    if not (math.isfinite(period) and period > 0):
        raise ValueError(f"period must be a positive number of seconds, got {period!r}")
    if max_samples < 2:
        raise ValueError(f"max_samples must be at least 2, got {max_samples!r}")
    first = recording.first_frame
    if first is None:
        raise ValueError(f"{recording.path} holds no readable frame")
    step = max(period, recording.duration / (max_samples - 1))
    count = int(math.floor(recording.duration / step + 1e-9)) + 1
    times: list[float] = []
    poses: list[NDArray[np.float64]] = []
    k = 0
    last = first.poses
    for t, f in recording.frames():
        while k < count and t > k * step + 1e-9:  # grid time k*step lies before this frame: the one before it
            times.append(k * step)
            poses.append(last)
            k += 1
        last = f.poses
    while k < count:
        times.append(k * step)
        poses.append(last)
        k += 1
    return Tracks(times=tuple(times), poses=tuple(poses), ids=tuple(int(i) for i in first.ids),
                  bounds=tuple(float(b) for b in first.bounds), period=step)  # type: ignore[arg-type]
