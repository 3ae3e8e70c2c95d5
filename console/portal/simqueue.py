"""The arena queue played on virtual time: how the portal's own claims (:meth:`~.service.PortalService.next_for`)
would run the jobs now in the arena queue, for checking the estimates it shows against the starts it then makes
(the tests) and for measuring them (``bench/bench_lab.py``).

:func:`play` starts each job the plan puts on an idle arena at the virtual time ``t`` (``setting up`` →
``running`` with ``started = t`` and the arena as ``placed``), ends it ``duration + true_overhead(job, arena)``
later (``done``, ``ended``) and moves on to the next event — through the real job store, the state machine and
the plan, with only the clock and the robots left out. Use it on a portal whose arenas run nothing else.
"""
from __future__ import annotations

import heapq
from collections.abc import Callable
from dataclasses import dataclass

from swarmdeck.console.portal.service import PortalService
from swarmdeck.console.portal.states import JobState


@dataclass(frozen=True)
class Played:
    """How one job went on virtual time: its arena, start and end (s, on the clock ``play`` was given)."""

    job_id: int
    arena: str
    started: float
    ended: float


def play(service: PortalService, now: float, true_overhead: Callable[[int, str], float],
         max_jobs: int = 100_000) -> list[Played]:
    """Run every job of the arena queue from virtual time ``now`` (module docstring); the jobs as they went, in
    the order they started. ``true_overhead(job_id, arena)``: the set-up and return time that job really takes
    there, s."""
    specs = {s.name: s for s in service.config.arena_specs()}
    running = {name: 0 for name in specs}
    ends: list[tuple[float, int, str]] = []
    out: list[Played] = []
    t = float(now)
    while len(out) < max_jobs:
        started = True
        while started:
            started = False
            for name, spec in specs.items():
                if running[name] >= spec.slots:
                    continue
                job = service.next_for(name, now=t)
                if job is None:
                    continue
                with service.store.transaction() as tx:
                    service.store.transition(tx, job.id, JobState.SETTING_UP, sources=(JobState.IN_ARENA_QUEUE,),
                                             started=t, placed=name)
                    service.store.transition(tx, job.id, JobState.RUNNING, sources=(JobState.SETTING_UP,))
                end = t + max(0.0, job.duration + true_overhead(job.id, name))
                heapq.heappush(ends, (end, job.id, name))
                out.append(Played(job.id, name, t, end))
                running[name] += 1
                started = True
        if not ends:
            return out
        t, job_id, name = heapq.heappop(ends)
        with service.store.transaction() as tx:
            service.store.transition(tx, job_id, JobState.DONE, sources=(JobState.RUNNING,), ended=t)
        running[name] -= 1
    return out
