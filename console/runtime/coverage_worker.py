"""Coverage a tick or two behind, on worker threads: the console at thousands of robots (issue 27 item 2).

At N = 5000 the coverage stage (bounded Voronoi, cell moments, Jacobian: ≈ 100 ms of CPU) is most of
a tick; the rest (sense, barrier, send, Frame) does not need it until the barrier. With the workers,
the ``coverage`` behaviour runs *pipelined*: at tick k it hands tick k's look-ahead points, run time
and density snapshot (taken on the loop thread) to the workers and returns the command they computed
from an earlier tick's, so coverage runs while the tick's barrier, Frame, subscribers and pacing run.
With ``depth`` 2 (the console's) two workers split the step: one builds tick k's Voronoi diagram
(:meth:`~swarmdeck.coverage.CoverageController.diagram`) while the other integrates tick k − 1's
moments, Jacobian and law (:meth:`~swarmdeck.coverage.CoverageController.finish`), and tick k runs
tick k − 2's command; with ``depth`` 1 one worker does the whole step and tick k runs tick k − 1's.
qhull, the numba kernels (``nogil``) and numpy's large-array loops release the GIL, so on two cores a
tick costs about max(loop, diagram, rest of coverage, all of it / 2) instead of their sum
(bench/RESULTS.md "console at any size").

What changes for the robots: the nominal velocity of tick k is the coverage law at tick k − depth's
positions (``depth`` control periods late; the first tick's is computed at once and used for the
first depth + 1 ticks). The barrier still certifies every command at the current poses, so safety
is unchanged, and the Frame's coverage (cells, centroids) is that of tick k − depth. It is
deterministic: tick k's command is always computed from exactly tick k − depth's inputs, never
"whatever was ready" (tests/console/test_console_coverage_worker.py). Workers that have not answered
within ``timeout`` s stop the robots for the tick (BehaviourError, counted by the loop's error
policy); the next tick waits for the same answer again. When the robots change (another N or other
ids) or the density object is replaced, the pipeline restarts as on the first tick.

When it is used: ``LoopConfig.coverage_worker`` (``[console] coverage_worker``, ``swarmdeck console
--coverage-worker``): "on" (two workers), "off", or "auto" (on from :data:`AUTO_MIN_ROBOTS` robots;
below that the tick is short and the synchronous path — the one the pipeline identity tests pin — is
kept).
"""
from __future__ import annotations

import weakref
from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from concurrent.futures import TimeoutError as FutureTimeout
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.runtime.behaviours import TickInput
from swarmdeck.console.runtime.params import BehaviourError, BehaviourParams
from swarmdeck.core.bounds import Bounds

__all__ = ["AUTO_MIN_ROBOTS", "PipelinedCoverage", "use_worker"]

#: ``coverage_worker = "auto"`` runs coverage on the worker from this many robots on (at N = 1000 the
#: synchronous console holds ≈ 29 ticks/s; bench/RESULTS.md "console at any size").
AUTO_MIN_ROBOTS = 2000

FloatArray = NDArray[np.float64]
_Result = tuple[FloatArray, Any]


def use_worker(setting: str, n_robots: int) -> bool:
    """Whether ``coverage_worker = setting`` ("on", "off", "auto") runs coverage on the worker for
    ``n_robots`` robots; ValueError naming a bad setting."""
    if setting == "auto":
        return int(n_robots) >= AUTO_MIN_ROBOTS
    if setting in ("on", "off"):
        return setting == "on"
    raise ValueError(f"coverage_worker must be 'auto', 'on' or 'off', got {setting!r}")


def _done(result: _Result) -> Future[_Result]:
    fut: Future[_Result] = Future()
    fut.set_result(result)
    return fut


class PipelinedCoverage:
    """The ``coverage`` behaviour, ``depth`` ticks behind on worker threads (module docstring).

    params, bounds, max_speed (m/s), safety_distance (m): as :class:`~swarmdeck.console.runtime.behaviours.
    Coverage`; depth: 1 (one worker: the whole step) or 2 (two workers: tick k's Voronoi diagram while
    tick k − 1's moments, Jacobian and law are computed; commands two ticks late); timeout: s a tick
    waits for the workers' answer (> 0). ``close()`` ends the workers.
    """

    name = "coverage"

    def __init__(self, params: BehaviourParams, bounds: Bounds, max_speed: float, safety_distance: float,
                 timeout: float = 10.0, depth: int = 2) -> None:
        from swarmdeck.coverage import CoverageConfig

        if not timeout > 0:
            raise ValueError(f"coverage worker timeout must be > 0 s, got {timeout!r}")
        if depth not in (1, 2):
            raise ValueError(f"coverage worker depth must be 1 or 2, got {depth!r}")
        self._config = CoverageConfig(law=params.law, kappa=params.kappa, max_speed=max_speed, bounds=bounds,
                                      safety_distance=safety_distance)
        self.timeout = float(timeout)
        self.depth = int(depth)
        self._ctrl: Any = None
        self._density: Any = None
        self._ids: NDArray[np.int64] | None = None
        self._queue: deque[Future[_Result]] = deque()
        self._pools = [ThreadPoolExecutor(max_workers=1, thread_name_prefix=f"swarmdeck-coverage-{k}")
                       for k in range(self.depth)]
        self.late = 0
        self._closed = False
        for pool in self._pools:
            weakref.finalize(self, pool.shutdown, wait=False, cancel_futures=True)

    def _restart(self, tick: TickInput) -> None:
        from swarmdeck.coverage import CoverageController

        self._ctrl = CoverageController(self._config, tick.density)
        self._density = tick.density
        self._queue.clear()

    def _submit(self, points: FloatArray, snap: Any, t: float) -> Future[_Result]:
        ctrl = self._ctrl
        if self.depth == 1:
            return self._pools[0].submit(ctrl.step, points, snap, t)
        diagram = self._pools[0].submit(ctrl.diagram, points)
        return self._pools[1].submit(lambda: ctrl.finish(diagram.result(), snap, t))

    def __call__(self, tick: TickInput) -> tuple[FloatArray, Any]:
        n = len(tick.points)
        ids = np.arange(n, dtype=np.int64) if tick.ids is None else np.asarray(tick.ids, dtype=np.int64)
        if (self._ctrl is None or tick.density is not self._density or self._ids is None
                or not np.array_equal(ids, self._ids)):
            self._restart(tick)
        self._ids = ids.copy()
        snap = tick.density.at(float(tick.t))              # on the loop thread: the operator's density now
        points, t = np.array(tick.points, dtype=float), float(tick.t)
        if self._closed:                                   # replaced while a tick still held it: at once
            return self._ctrl.step(points, snap, t)
        if not self._queue:                                # first tick: this tick's coverage, now, used
            first = _done(self._ctrl.step(points, snap, t))  # for this tick and the next `depth` ticks
            self._queue.extend([first] * self.depth)
            return first.result()
        try:
            result = self._queue[0].result(timeout=self.timeout)
        except FutureTimeout:
            self.late += 1
            raise BehaviourError(f"coverage worker late: no answer within {self.timeout:g} s "
                                 "(robots stopped for this tick)") from None
        except BaseException:
            self._queue.clear()                            # its error is this tick's; start afresh next tick
            raise
        self._queue.popleft()
        self._queue.append(self._submit(points, snap, t))
        return result

    def health(self) -> str:
        """The console's health line for the workers: how many ticks behind, and how often they were late."""
        return f"coverage worker: {self.depth} tick{'s' if self.depth > 1 else ''} behind, {self.late} ticks late"

    def close(self) -> None:
        """End the worker threads (a step still running finishes on its own; its result is dropped)."""
        self._closed = True
        self._queue.clear()
        for pool in self._pools:
            pool.shutdown(wait=False, cancel_futures=True)
