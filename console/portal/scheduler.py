"""The plan of the arena queue: which arena (and slot) each waiting job goes to and when it starts and ends.

One function, :func:`plan`, decides both the estimated start and end times researchers see (the pages, the API,
``swarmdeck jobs``) and the jobs the arenas claim (:meth:`~.service.PortalService.claim_for_arena` takes the
first job the plan puts on that arena *now*), so the estimates are what the claims do, recomputed every time
the queue moves. Pure Python, no I/O.

Model (all times UNIX s):

* A **lane** is one slot of one arena (an arena runs ``slots`` jobs at once; one without regions has one lane).
  It is busy over the intervals of the jobs on it now (started → started + occupancy, at least "now"), and
  unavailable altogether while its arena is stopped or its remote runner is not connected.
* A job **occupies** a lane for its declared duration plus its arena's measured overhead (set-up and return:
  the median of ``ended − started − duration`` over the arena's recent runs; :func:`overhead`).
* **Reservations** (:class:`Window`): while one covers an arena (or one of its slots), only the jobs of the
  users it names may run there.
* Jobs are planned **in queue order** (which is fair-share order: :meth:`.jobstore.JobStore.insert`); each takes
  the earliest gap, on any lane that fits it (robots, physical/simulated, a named arena), that is long enough
  and crosses no reservation that excludes its owner — a short job may fill a gap before a reservation
  (backfilling) but never delays a job planned before it. Ties go to an idle lane, then to the arenas' order.
"""
from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from statistics import median

#: a running job whose estimated end has passed ends "any moment": this long after now, s (so that an idle lane,
#: which can start a job *now*, is preferred to it)
OVERDUE_S = 1e-3
#: the set-up and return time assumed for an arena that has not run a job yet, s
DEFAULT_OVERHEAD_S = 10.0
#: runs the overhead estimate is taken over (the most recent)
OVERHEAD_RUNS = 20


@dataclass(frozen=True)
class Pending:
    """A waiting job as the plan needs it: id, owner, robots, declared duration s, the arena it asked for (None:
    any), what it needs (``either`` | ``physical`` | ``simulated``) and the arena bounds it was verified against
    (``(x_min, x_max, y_min, y_max)`` m as its script sees them; None: any — it goes only on a lane of these)."""

    id: int
    user_id: int
    robots: int
    duration: float
    arena: str | None = None
    needs: str = "either"
    bounds: tuple[float, float, float, float] | None = None


@dataclass(frozen=True)
class Window:
    """A reservation: ``arena`` (and ``slot``; None: every slot) is reserved for ``user_ids`` over [start, end)."""

    arena: str
    start: float
    end: float
    user_ids: frozenset[int]
    slot: int | None = None

    def blocks(self, user_id: int, arena: str, slot: int, t0: float, t1: float) -> bool:
        """Whether a job of ``user_id`` on (arena, slot) over [t0, t1) would cross this reservation."""
        return (arena == self.arena and (self.slot is None or self.slot == slot) and user_id not in self.user_ids
                and t0 < self.end and self.start < t1)


@dataclass
class Lane:
    """One slot of one arena: its capacity, the intervals it is busy (module docstring) and the bounds its jobs'
    scripts see (m; None: not checked) — a job verified against other bounds does not fit it. ``conflicts``: the
    slots of its arena that are busy whenever it is and the other way round (regions allocated per job: a region
    and the regions inside or around it); a job placed on it makes them busy too."""

    arena: str
    slot: int
    kind: str
    robots: int
    busy: list[tuple[float, float]] = field(default_factory=list)
    bounds: tuple[float, float, float, float] | None = None
    conflicts: tuple[int, ...] = ()  # slots of the same arena busy whenever this one is (nested regions)

    def fits(self, job: Pending) -> bool:
        return (job.robots <= self.robots and job.needs in ("either", self.kind) and job.arena in (None, self.arena)
                and (job.bounds is None or self.bounds is None or tuple(job.bounds) == tuple(self.bounds)))

    def earliest(self, job: Pending, length: float, now: float, windows: Sequence[Window]) -> float:
        """The earliest start ≥ now of a gap of ``length`` s on this lane that crosses no busy interval and no
        reservation excluding the job's owner."""
        blocks = sorted([*self.busy, *((w.start, w.end) for w in windows
                                       if w.blocks(job.user_id, self.arena, self.slot, -math.inf, math.inf))])
        t = now
        moved = True
        while moved:
            moved = False
            for b0, b1 in blocks:
                if t < b1 and b0 < t + max(length, 1e-9):
                    t, moved = b1, True
        return t

    @property
    def idle_now(self) -> bool:
        return not self.busy


@dataclass(frozen=True)
class Placement:
    """Where and when a job is planned: arena, slot, start and end, UNIX s."""

    arena: str
    slot: int
    start: float
    end: float


def overhead(runs: Sequence[tuple[float, float, float]]) -> float:
    """An arena's set-up and return time, s: the median of ``ended − started − duration`` over ``runs``
    ((started, ended, declared duration) of its recent runs); :data:`DEFAULT_OVERHEAD_S` without any."""
    if not runs:
        return DEFAULT_OVERHEAD_S
    return float(median(e - s - d for s, e, d in runs[-OVERHEAD_RUNS:]))


def occupancy(duration: float, arena_overhead: float) -> float:
    """How long a job of declared ``duration`` s holds a lane, s (never negative)."""
    return max(0.0, float(duration) + float(arena_overhead))


def plan(pending: Sequence[Pending], lanes: Sequence[Lane], windows: Sequence[Window], now: float,
         overheads: Mapping[str, float]) -> dict[int, Placement]:
    """The placement of each of ``pending`` (in queue order) that some lane can take (module docstring); a job no
    available lane fits is absent. ``lanes`` are copied, never changed; ``overheads``: arena → s."""
    work = [Lane(l.arena, l.slot, l.kind, l.robots, [(b0, max(b1, now + OVERDUE_S)) for b0, b1 in l.busy], l.bounds,
                 l.conflicts) for l in lanes]
    index = {(l.arena, l.slot): k for k, l in enumerate(work)}
    out: dict[int, Placement] = {}
    for job in pending:
        best: tuple[float, int, int] | None = None
        for k, lane in enumerate(work):
            if not lane.fits(job):
                continue
            length = occupancy(job.duration, overheads.get(lane.arena, DEFAULT_OVERHEAD_S))
            t = lane.earliest(job, length, now, windows)
            key = (t, 0 if lane.idle_now else 1, k)
            if best is None or key < best:
                best = key
        if best is None:
            continue
        lane = work[best[2]]
        start = best[0]
        end = start + occupancy(job.duration, overheads.get(lane.arena, DEFAULT_OVERHEAD_S))
        lane.busy.append((start, end))
        for slot in lane.conflicts:  # nested regions: the regions inside and around it are taken as long
            other = index.get((lane.arena, slot))
            if other is not None:
                work[other].busy.append((start, end))
        out[job.id] = Placement(lane.arena, lane.slot, start, end)
    return out
