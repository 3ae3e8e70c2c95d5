"""Closed-form recordings for the multi-run player and ``swarmdeck compare`` tests (issue 31 item 4).

:func:`straight_run` writes a recording whose every number is known in closed form: robot 0 stands at the
origin, robot 1 drives from (``x0``, 0) towards it along −x at ``speed`` m/s, the others stand in a row at
y = 0.5 m; frames every ``dt`` s (a power of two: exact times), events at chosen ticks, the barrier's
intervention on robot 1 during chosen ticks, a coverage cost H = 1 + 0.1 k at tick k.
"""
from __future__ import annotations

import os
from collections.abc import Iterable, Mapping

import numpy as np

from swarmdeck.console.runtime.frame import BarrierFrame, CoverageFrame, Frame

DT = 0.0625  # s (1/16: every frame time is exact)
BOUNDS = (-1.6, 1.6, -1.0, 1.0)


def straight_frame(k: int, *, n: int = 3, dt: float = DT, x0: float = 0.5, speed: float = 0.2,
                   bounds: tuple[float, float, float, float] = BOUNDS, events: tuple[str, ...] = (),
                   intervening: bool = False, failed: bool = False, estop: bool = False, t0: float = 100.0) -> Frame:
    """Tick ``k`` of the closed-form run (module docstring); the loop clock starts at ``t0`` s."""
    t = k * dt
    poses = np.zeros((n, 3))
    poses[1] = (x0 - speed * t, 0.0, np.pi)
    poses[2:, 0] = -1.0 + 0.3 * np.arange(n - 2)
    poses[2:, 1] = 0.5
    v = np.zeros(n)
    v[1] = 0.0 if estop else speed
    inter = np.zeros(n)
    if intervening:
        inter[1] = 0.01
    barrier = BarrierFrame(ok=not failed, status="failed" if failed else "ok", intervention=inter)
    coverage = CoverageFrame(centroids=poses[:, :2], masses=np.ones(n), edges=np.empty((0, 2, 2)),
                             neighbours=np.empty((0, 2), dtype=np.int64), cost_H=1.0 + 0.1 * k,
                             mean_centroid_distance=0.0)
    return Frame(tick=k, time=t0 + t, poses=poses, ids=np.arange(n), nominal=np.zeros((n, 2)),
                 safe=np.zeros((n, 2)), v=v, w=np.zeros(n), dt=dt, run_time=t, bounds=bounds, barrier=barrier,
                 coverage=coverage, events=events, run_state="estop" if estop else "running")


def straight_run(path: str | os.PathLike[str], ticks: int = 33, *, events: Mapping[int, str] | None = None,
                 intervening: Iterable[int] = (), failed: Iterable[int] = (), estop: Iterable[int] = (),
                 chunk_size: int | None = None, **kwargs: object) -> str:
    """Record ticks 0 … ``ticks`` − 1 of the closed-form run to ``path`` (MCAP chunks of ``chunk_size`` bytes:
    small ones make a file whose cut keeps a readable prefix); returns the path as a string."""
    from swarmdeck.console.recording.recorder import Recorder, RecorderConfig

    events = dict(events or {})
    inter, bad, stop = set(intervening), set(failed), set(estop)
    config = RecorderConfig() if chunk_size is None else RecorderConfig(chunk_size=chunk_size)
    with Recorder(path, {"config": {"source": "closed form"}}, config) as rec:
        for k in range(ticks):
            rec.write_frame(straight_frame(k, events=(events[k],) if k in events else (), intervening=k in inter,
                                           failed=k in bad, estop=k in stop, **kwargs))  # type: ignore[arg-type]
    return str(path)
