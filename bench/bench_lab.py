"""Benchmark: several arenas behind one portal (issue 30) — jobs per hour with two arenas against one, and the
error of the estimated start times the portal shows.

Run: ``.venv/bin/python bench/bench_lab.py [--jobs 8] [--duration 30] [--robots 6] [--sim-jobs 400]``
(prints markdown tables).

1. **Real runs** (this process): the portal service with one, then two simulated arenas (each an
   :class:`~swarmdeck.console.portal.runner.ArenaRunner` in real time, 12 robots on the chargers — the same runner
   the server starts per ``--arena NAME=sim``), the user code in the sandbox. Per configuration: one warm-up job
   per arena (the portal measures each arena's set-up and return), then ``--jobs`` jobs of ``--robots`` robots and
   ``--duration`` s from three researchers, queued at once (verification skipped: put in the queue as an
   accepting verification would). The estimated starts are read right after queueing (``with_eta``, what the API
   and ``swarmdeck jobs`` show); jobs per hour = jobs / (last end − first start) · 3600; ETA error = actual
   ``started`` − estimated start, per job.
2. **Simulated queue** (virtual time, :func:`swarmdeck.console.portal.simqueue.play`: the portal's real job store,
   plan and claims with only the clock and robots left out): ``--sim-jobs`` jobs of ``--robots`` robots and
   ``--duration`` s, set-up and return 12 s ± 4 s per job (uniform, seeded), on one and on two arenas: jobs per
   hour and the ETA error (median, 90th percentile) over the whole queue.

The same-process baseline is :func:`harness.baseline`.
"""
from __future__ import annotations

import argparse
import json
import random
import statistics
import tempfile
import time
from pathlib import Path

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

from swarmdeck.console.portal.states import JobState

SPIN = ("import numpy as np\n"
        "def experiment(arena):\n"
        "    while True:\n"
        "        arena.set_unicycle(np.full(arena.n, 0.02), np.full(arena.n, 0.5))\n"
        "        arena.step()\n")


def _queue(service, user, robots: int, duration: float, name: str, arena: str | None = None) -> int:
    manifest = {"name": name, "robots": robots, "duration": duration, **({"arena": arena} if arena else {})}
    job = service.submit(user, "spin.py", SPIN.encode(), json.dumps(manifest))
    with service.db.transaction() as tx:
        service.db.transition(tx, job.id, JobState.VERIFYING)
        service.db.transition(tx, job.id, JobState.AWAITING_APPROVAL, verdict="accepted")
        service.db.transition(tx, job.id, JobState.IN_ARENA_QUEUE)
    service.notify()
    return int(job.id)


def _wait(service, ids: list[int], timeout: float) -> None:
    from swarmdeck.console.portal.states import FINAL

    deadline = time.monotonic() + timeout
    while any(service.job_state(i) not in FINAL for i in ids):
        if time.monotonic() > deadline:
            raise RuntimeError(f"jobs not done in {timeout} s: {[(i, service.job_state(i)) for i in ids]}")
        time.sleep(0.2)


def real(n_arenas: int, n_jobs: int, robots: int, duration: float, workdir: Path) -> dict:
    from swarmdeck.console.portal.arenas import ArenaSpec
    from swarmdeck.console.portal.quotas import Quotas
    from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
    from swarmdeck.console.portal.service import PortalConfig, PortalService
    from swarmdeck.console.portal.submission import Limits

    names = [f"arena{k}" for k in range(n_arenas)]
    service = PortalService(PortalConfig(data=workdir / f"data{n_arenas}", limits=Limits(fleet=12),
                                         quotas=Quotas(None, None, None),
                                         arenas=tuple(ArenaSpec(n, robots=12) for n in names)))
    users = [service.accounts.add_user(n, "researcher")[0] for n in ("ann", "ben", "cat")]
    runners = [ArenaRunner(service, ArenaSettings(fleet=12, seed=3 + k, name=n), poll_s=0.1)
               for k, n in enumerate(names)]
    service.runners = {r.settings.name or "": r for r in runners}
    for r in runners:
        r.start()
    try:
        warm = [_queue(service, users[0], robots, duration, f"warm-up {n}", arena=n) for n in names]
        _wait(service, warm, 600)
        ids = [_queue(service, users[k % 3], robots, duration, f"job {k}") for k in range(n_jobs)]
        eta = {j.id: j.eta_start for j in service.with_eta(service.store.queue())}
        _wait(service, ids, 60 * (n_jobs + 2) * max(1.0, duration / 10))
        jobs = [service.store.get(i) for i in ids]
    finally:
        for r in runners:
            r.stop()
        service.close()
    first, last = min(j.started for j in jobs), max(j.ended for j in jobs)
    errors = [j.started - eta[j.id] for j in jobs if eta.get(j.id) is not None]
    return {"arenas": n_arenas, "jobs": n_jobs, "wall_s": last - first, "per_hour": n_jobs / (last - first) * 3600,
            "done": sum(j.state == JobState.DONE for j in jobs), "errors": errors,
            "placed": {n: sum(j.placed == n for j in jobs) for n in names}}


def simulated(n_arenas: int, n_jobs: int, robots: int, duration: float, workdir: Path, seed: int = 7) -> dict:
    from swarmdeck.console.portal.arenas import ArenaSpec
    from swarmdeck.console.portal.quotas import Quotas
    from swarmdeck.console.portal.service import PortalConfig, PortalService
    from swarmdeck.console.portal.simqueue import play
    from swarmdeck.console.portal.submission import Limits

    names = [f"arena{k}" for k in range(n_arenas)]
    service = PortalService(PortalConfig(data=workdir / f"sim{n_arenas}", limits=Limits(fleet=50),
                                         quotas=Quotas(None, None, None),
                                         arenas=tuple(ArenaSpec(n, robots=50) for n in names)))
    users = [service.accounts.add_user(n, "researcher")[0] for n in ("ann", "ben", "cat")]
    rng = random.Random(seed)
    jitter = {}

    def overhead(job_id: int, arena: str) -> float:
        return jitter.setdefault(job_id, rng.uniform(8.0, 16.0))

    t0 = 1_000_000.0
    warm = [_queue(service, users[0], robots, duration, f"warm-up {k}") for k in range(3 * n_arenas)]
    t0 = max(p.ended for p in play(service, t0, overhead))
    ids = [_queue(service, users[k % 3], robots, duration, f"job {k}") for k in range(n_jobs)]
    cpu, eta = harness.timed(lambda: service.plan(service.store.waiting_in_order(), t0))
    played = {p.job_id: p for p in play(service, t0, overhead)}
    service.close()
    del warm
    first, last = min(played[i].started for i in ids), max(played[i].ended for i in ids)
    return {"arenas": n_arenas, "jobs": n_jobs, "per_hour": n_jobs / (last - first) * 3600,
            "errors": [played[i].started - eta[i].start for i in ids], "plan_cpu_s": cpu}


def _pct(values: list[float], q: float) -> float:
    s = sorted(abs(v) for v in values)
    return s[min(len(s) - 1, int(q * (len(s) - 1) + 0.5))] if s else float("nan")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=8)
    ap.add_argument("--duration", type=float, default=30.0)
    ap.add_argument("--robots", type=int, default=6)
    ap.add_argument("--sim-jobs", type=int, default=400)
    ap.add_argument("--skip-real", action="store_true")
    args = ap.parse_args()
    print(harness.machine())
    print(f"baseline (sort 1e5 x10, thread CPU): {harness.baseline().median * 1e3:.1f} ms")
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        print(f"\nsimulated queue: {args.sim_jobs} jobs of {args.robots} robots and {args.duration:g} s, set-up and "
              "return 12 ± 4 s")
        print(harness.table_header(["arenas", "jobs/hour", "ETA error median s", "ETA error p90 s", "plan CPU ms"],
                                   [False, True, True, True, True]))
        sim = [simulated(n, args.sim_jobs, args.robots, args.duration, work) for n in (1, 2)]
        for r in sim:
            print(harness.table_row(r["arenas"], f"{r['per_hour']:.0f}", f"{_pct(r['errors'], 0.5):.1f}",
                                    f"{_pct(r['errors'], 0.9):.1f}", f"{r['plan_cpu_s'] * 1e3:.0f}"))
        print(f"two arenas / one: {sim[1]['per_hour'] / sim[0]['per_hour']:.2f}x")
        if args.skip_real:
            return
        print(f"\nreal runs (real time, sandboxed): {args.jobs} jobs of {args.robots} robots and {args.duration:g} s")
        print(harness.table_header(["arenas", "wall s", "jobs/hour", "done", "placed", "ETA error median s",
                                    "ETA error p90 s"], [False, True, True, True, False, True, True]))
        rows = [real(n, args.jobs, args.robots, args.duration, work) for n in (1, 2)]
        for r in rows:
            print(harness.table_row(r["arenas"], f"{r['wall_s']:.0f}", f"{r['per_hour']:.0f}", r["done"],
                                    " ".join(f"{k}:{v}" for k, v in r["placed"].items()),
                                    f"{statistics.median(abs(e) for e in r['errors']):.1f}",
                                    f"{_pct(r['errors'], 0.9):.1f}"))
        print(f"two arenas / one: {rows[1]['per_hour'] / rows[0]['per_hour']:.2f}x")


if __name__ == "__main__":
    main()
