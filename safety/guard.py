"""The guard of a bypassed barrier: when to switch the barrier back on, and the last-resort brake.

A run without the barrier (an operator approved that job's bypass, DESIGN.md "Trust boundary") is
never without protection. Every tick, on the trusted side (:func:`swarmdeck.devices.pipeline.certify_bypassed`):

* the walls and fixed obstacles (docked robots) stay hard constraints: the same certified filter with
  ``BarrierConfig(pairs=False)``;
* the full barrier is evaluated in monitor mode, and :func:`check` trips — the barrier comes back for the
  rest of the run — the first time

  - a pair of controlled points (the look-ahead points the barrier's D_s applies to) would come closer
    than ``GuardConfig.guard_distance`` during the next tick under the commands about to be sent
    (:func:`approaches`: the closest approach of the two points moving linearly from where they are to
    where those commands put them), or
  - the full barrier would have changed some robot's command by more than ``GuardConfig.max_intervention``
    (m/s of its look-ahead point) beyond what the walls and obstacles already changed, or
  - the full barrier could not be evaluated (the monitor failed);

* :func:`brake` then stops (zero command) every robot that would still bring a pair closer than the guard
  distance during the next tick (and closer than it is now): a robot standing still cannot approach, so
  with exact motion prediction no pair ever comes closer than the guard distance, whatever the script does.
  It holds from the first bypassed tick to the end of the run, after a revocation too (the barrier's
  discrete-time drift is a few 0.1 mm per tick). :func:`assess` gives the trip verdict and the brake of a
  tick from one k-d tree query.

Re-enabling rather than stopping: verification's *wrapped* runs already showed the script runs with the
barrier, so switching it back on puts the run in the mode that was verified; it goes on safely and the
researcher still gets data (stopping would throw the run away for what may be one close pass). The brake
is the last resort for what the barrier lets drift.

The guard distance lies between contact (the rps test: centres 0.025 m ahead of the axle at most 0.135 m
apart, REFERENCE.md §1) and D_s (0.17 m between look-ahead points ℓ = 0.03 m ahead): look-ahead points
0.15 m apart put the rps collision centres at least 0.14 m apart (each within 0.005 m of its look-ahead
point). Everything here is vectorised over pairs found by a k-d tree (no N × N matrix).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: m: closest approaches within this of a bound count as meeting it (round-off of the prediction)
TOLERANCE = 1e-9


@dataclass(frozen=True)
class GuardConfig:
    """The guard of a bypassed barrier (module docstring).

    Attributes:
        guard_distance: m between look-ahead points; no pair may come closer (0.15: between contact,
            0.135 m between the rps collision centres, and D_s = 0.17 m). Keep it ≤ the barrier's D_s,
            else the barrier itself lets pairs closer and the brake has to stop them.
        max_intervention: m/s; the full barrier changing a look-ahead velocity by more than this (beyond
            the walls' and obstacles' own change) revokes the bypass (0.1: half the top speed; a head-on
            approach at full speed trips it ≈ 0.37 m apart).
    """

    guard_distance: float = 0.15
    max_intervention: float = 0.1

    def __post_init__(self) -> None:
        for name in ("guard_distance", "max_intervention"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                    or value <= 0:
                raise ValueError(f"GuardConfig: {name} must be a finite number > 0, got {value!r}")


@dataclass(frozen=True)
class GuardCheck:
    """One tick's verdict of :func:`check`.

    Attributes:
        trip: the barrier must come back now.
        reason: why, in words (None when not tripped).
        closest: the smallest predicted closest approach over the next tick among the pairs looked at, m
            (inf when no pair is near).
        pair: the indices of that pair (-1, -1 when none).
        intervention: the largest extra change the full barrier would make, m/s.
    """

    trip: bool
    reason: str | None
    closest: float
    pair: tuple[int, int]
    intervention: float


def _candidates(p0: FloatArray, step: FloatArray, distance: float) -> IntArray:
    """``(K, 2)`` pairs ``i < j`` of points ``p0`` that can come within ``distance`` (m) when each moves by at
    most the largest of ``step`` (k-d tree, radius ``distance`` + twice the largest displacement)."""
    if p0.shape[0] < 2:
        return np.zeros((0, 2), dtype=np.int64)
    reach = float(np.sqrt(np.max(step[:, 0] * step[:, 0] + step[:, 1] * step[:, 1])))
    # an unbalanced, non-compacted tree builds faster for one query (the same pairs)
    from scipy.spatial import cKDTree  # lazy: see test_devices_rps_startup_imports

    tree = cKDTree(p0, balanced_tree=False, compact_nodes=False)
    pairs = tree.query_pairs(distance + 2.0 * reach + TOLERANCE, output_type="ndarray")
    return pairs.astype(np.int64, copy=False).reshape(-1, 2)


def _closest(e0: FloatArray, de: FloatArray) -> FloatArray:
    """Closest approach over the tick of pairs whose offset goes linearly from ``e0`` to ``e0 + de`` (K, 2), m."""
    dd = de[:, 0] * de[:, 0] + de[:, 1] * de[:, 1]
    s = np.clip(-(e0[:, 0] * de[:, 0] + e0[:, 1] * de[:, 1]) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
    return np.hypot(e0[:, 0] + s * de[:, 0], e0[:, 1] + s * de[:, 1])


def approaches(p0: FloatArray, p1: FloatArray, distance: float) -> tuple[IntArray, FloatArray, FloatArray]:
    """Pairs of points moving linearly from ``p0`` to ``p1`` (each ``(N, 2)``, m) over one tick that come
    within ``distance`` (m) of each other: ``(pairs (K, 2) i < j, closest approach (K,), distance now (K,))``.
    """
    step = p1 - p0
    pairs = _candidates(p0, step, distance)
    if pairs.shape[0] == 0:
        return pairs, np.zeros(0), np.zeros(0)
    i, j = pairs[:, 0], pairs[:, 1]
    e0 = p0[i] - p0[j]
    closest = _closest(e0, step[i] - step[j])
    near = closest < distance
    return pairs[near], closest[near], np.linalg.norm(e0[near], axis=1)


def _verdict(config: GuardConfig, pairs: IntArray, closest: FloatArray, intervention: FloatArray,
             monitor_ok: bool, monitor_status: str, label: NDArray[np.integer]) -> GuardCheck:
    """The trip rules (module docstring) on robot pairs ``pairs`` (K, 2) and their closest approaches (K,)."""
    worst = float(intervention.max()) if intervention.size else 0.0
    if pairs.shape[0]:
        k = int(np.argmin(closest))
        near, pair = float(closest[k]), (int(label[pairs[k, 0]]), int(label[pairs[k, 1]]))
    else:
        near, pair = math.inf, (-1, -1)
    reason = None
    if not monitor_ok:
        reason = f"the barrier could not be evaluated ({monitor_status})"
    elif near < config.guard_distance - TOLERANCE:
        reason = (f"robots {pair[0]} and {pair[1]} would come {near:.3f} m apart "
                  f"(guard distance {config.guard_distance:g} m)")
    elif worst > config.max_intervention:
        robot = int(label[int(np.argmax(intervention))])
        reason = (f"the barrier would have changed robot {robot}'s command by {worst:.3f} m/s "
                  f"(threshold {config.max_intervention:g} m/s)")
    return GuardCheck(reason is not None, reason, near, pair, worst)


def check(config: GuardConfig, p0: FloatArray, p1: FloatArray, intervention: FloatArray,
          monitor_ok: bool = True, monitor_status: str = "", names: NDArray[np.integer] | None = None) -> GuardCheck:
    """Whether the bypass must be revoked this tick (module docstring).

    Args:
        p0, p1: ``(N, 2)`` look-ahead points now and after the next tick under the commands about to be sent, m.
        intervention: ``(N,)`` how much more the full barrier would change each robot's look-ahead velocity than
            the walls and obstacles do, m/s.
        monitor_ok, monitor_status: whether the full barrier could be evaluated, and its status.
        names: ``(N,)`` the robots' ids for the reason and ``GuardCheck.pair`` (default 0…N−1).
    """
    label = np.arange(p0.shape[0]) if names is None else np.asarray(names).reshape(-1)
    pairs, closest, _ = approaches(p0, p1, config.guard_distance)
    return _verdict(config, pairs, closest, intervention, monitor_ok, monitor_status, label)


class _Approaches:
    """Robots ``p0 → p1`` (N) and fixed points (M) as one set; the candidate pairs of one k-d tree query."""

    def __init__(self, p0: FloatArray, p1: FloatArray, distance: float, fixed: FloatArray | None) -> None:
        self.n = p0.shape[0]
        extra = None if fixed is None else np.asarray(fixed, dtype=float).reshape(-1, 2)
        if extra is None or len(extra) == 0:
            a0, self.step = p0, p1 - p0
        else:
            a0, self.step = np.concatenate([p0, extra]), np.concatenate([p1 - p0, np.zeros_like(extra)])
        pairs = _candidates(a0, self.step, distance)  # every pair that could come that close, whoever stops
        self.i, self.j = pairs[:, 0], pairs[:, 1]
        self.e0 = a0[self.i] - a0[self.j]
        self.closest = _closest(self.e0, self.step[self.i] - self.step[self.j])

    def stops(self, distance: float) -> NDArray[np.bool_]:
        """(N,) robots to stop so that no pair comes closer than ``distance`` nor than it is (see :func:`brake`)."""
        stopped = np.zeros(self.n, dtype=bool)
        if self.i.size == 0:
            return stopped
        bound = np.minimum(distance, np.hypot(self.e0[:, 0], self.e0[:, 1])) - TOLERANCE
        moving = np.concatenate([np.ones(self.n, dtype=bool), np.zeros(len(self.step) - self.n, dtype=bool)])
        closest = self.closest
        for _ in range(self.n + 1):
            bad = closest < bound
            if not bad.any():
                break
            robots = np.concatenate([self.i[bad], self.j[bad]])
            moving[robots] = False
            stopped[robots[robots < self.n]] = True
            step = np.where(moving[:, None], self.step, 0.0)
            closest = _closest(self.e0, step[self.i] - step[self.j])
        return stopped


def brake(p0: FloatArray, p1: FloatArray, distance: float, fixed: FloatArray | None = None) -> NDArray[np.bool_]:
    """``(N,)`` robots to stop this tick so that no pair comes closer than ``distance`` (m) during it, nor
    closer than it is now (module docstring).

    ``p0``, ``p1``: ``(N, 2)`` look-ahead points now and after the tick under the commands about to be sent;
    ``fixed``: ``(M, 2)`` points that do not move (docked robots, unseen robots). A stopped robot's point stays
    at ``p0``; robots are stopped until no moving robot takes part in an approach (at most N rounds, usually one).
    """
    return _Approaches(p0, p1, distance, fixed).stops(distance)


def assess(config: GuardConfig, p0: FloatArray, p1: FloatArray, intervention: FloatArray,
           fixed: FloatArray | None = None, monitor_ok: bool = True, monitor_status: str = "",
           names: NDArray[np.integer] | None = None) -> tuple[GuardCheck, NDArray[np.bool_]]:
    """:func:`check` and :func:`brake` (at the guard distance) of the same tick from one k-d tree query: the
    verdict, and the robots to stop if the commands that give ``p1`` are sent (the brake of a tripped tick must
    be recomputed for the full barrier's commands)."""
    label = np.arange(p0.shape[0]) if names is None else np.asarray(names).reshape(-1)
    tick = _Approaches(p0, p1, config.guard_distance, fixed)
    robots = (tick.j < tick.n) & (tick.closest < config.guard_distance)
    if robots.any():
        pairs, closest = np.column_stack((tick.i[robots], tick.j[robots])), tick.closest[robots]
    else:
        pairs, closest = np.zeros((0, 2), dtype=np.int64), np.zeros(0)
    verdict = _verdict(config, pairs, closest, np.asarray(intervention, dtype=float), monitor_ok, monitor_status,
                       label)
    return verdict, tick.stops(config.guard_distance)


__all__ = ["GuardConfig", "GuardCheck", "approaches", "assess", "check", "brake", "TOLERANCE"]
