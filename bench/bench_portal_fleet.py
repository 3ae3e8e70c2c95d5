"""Benchmark: the portal arena's fleet upkeep per job — set-up from the chargers and return, next to the run itself.

Run: ``.venv/bin/python bench/bench_portal_fleet.py [--fleet 12] [--jobs 3] [--robots 3 6 10]`` (prints a markdown
table).

In this process: the portal service and its arena runner on the simulated arena in ``--fast`` mode (the set-up and
the return are computed as fast as they go, as the server does for a simulated fleet) with a fleet of ``--fleet``
robots docked on the chargers. For each N of ``--robots``, ``--jobs`` jobs of N robots and 2 s (a script that holds
still), random start poses (a fresh draw per job), queued one after the other (verification skipped: the jobs are
put in the queue as an accepting verification would). Per job, from its ``run.json``: the set-up's and the return's
simulated seconds (what they take on real robots, in real time), their wall seconds here, the largest pose error
after the set-up, escapes and collisions; the baseline in the same process is the job's own wall time from claim
to end without set-up and return (sandbox start-up, the 2 s run, the recording and the exports).
"""
from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

from swarmdeck.console.portal.states import JobState

STILL = "def experiment(arena):\n    while True:\n        arena.step()\n"


def run(fleet: int, n_jobs: int, sizes: list[int], workdir: Path) -> list[dict]:
    from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
    from swarmdeck.console.portal.service import PortalConfig, PortalService
    from swarmdeck.console.portal.states import FINAL, JobState

    service = PortalService(PortalConfig(data=workdir / "data", trusted=True))
    user, _ = service.accounts.add_user("bench", "researcher")
    runner = ArenaRunner(service, ArenaSettings(fleet=fleet, fast=True, seed=11), poll_s=0.05).start()
    service.arena = runner
    rows = []
    try:
        for n in sizes:
            ids = []
            for k in range(n_jobs):
                job = service.submit(user, "still.py", STILL.encode(),
                                     json.dumps({"name": f"N={n} #{k}", "robots": n, "duration": 2.0}))
                with service.db.transaction() as tx:
                    service.db.transition(tx, job.id, JobState.VERIFYING)
                    service.db.transition(tx, job.id, JobState.AWAITING_APPROVAL, verdict="accepted")
                    service.db.transition(tx, job.id, JobState.IN_ARENA_QUEUE)
                ids.append(job.id)
            service.notify()
            while not all(service.job_state(j) in FINAL for j in ids):
                time.sleep(0.05)
            while runner.current_job is not None:
                time.sleep(0.05)
            for jid in ids:
                job = service.job(user, jid)
                run_json = json.loads((service.job_dir(jid) / "run.json").read_text())
                s, r = run_json.get("setup", {}), run_json.get("return", {})
                wall = job.ended - job.started
                rows.append({"n": n, "id": jid, "state": job.state, "setup_sim": s.get("seconds"),
                             "setup_wall": s.get("wall_s"), "return_sim": r.get("seconds"),
                             "return_wall": r.get("wall_s"), "error_cm": 100 * (s.get("max_position_error") or 0),
                             "error_deg": s.get("max_heading_error_deg"), "escapes": s.get("escapes", 0),
                             "collisions": (s.get("collisions") or 0) + (r.get("collisions") or 0),
                             "baseline_wall": wall - (s.get("wall_s") or 0) - (r.get("wall_s") or 0),
                             "ready": runner.fleet_status()["ready"]})
    finally:
        runner.stop()
        service.close()
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fleet", type=int, default=12)
    ap.add_argument("--jobs", type=int, default=3)
    ap.add_argument("--robots", type=int, nargs="+", default=[3, 6, 10])
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        rows = run(args.fleet, args.jobs, args.robots, Path(tmp))
    med = statistics.median
    print(f"\nfleet upkeep per job: fleet of {args.fleet}, {args.jobs} jobs per N, "
          f"{harness.machine()}\n")
    print("| N | jobs done | set-up simulated s (median, max) | set-up wall s | return simulated s (median, max) "
          "| return wall s | job without upkeep, wall s (baseline) | upkeep wall / baseline | largest pose error "
          "| escapes | collisions | arena ready after the jobs |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for n in args.robots:
        rs = [r for r in rows if r["n"] == n]
        ok = [r for r in rs if r["state"] == JobState.DONE]
        if not ok:
            print(f"| {n} | 0/{len(rs)} | | | | | | | | | | |")
            continue
        up = med(r["setup_wall"] + r["return_wall"] for r in ok)
        base = med(r["baseline_wall"] for r in ok)
        print(f"| {n} | {len(ok)}/{len(rs)} | {med(r['setup_sim'] for r in ok):.1f} ({max(r['setup_sim'] for r in ok):.1f}) "
              f"| {med(r['setup_wall'] for r in ok):.2f} | {med(r['return_sim'] for r in ok):.1f} "
              f"({max(r['return_sim'] for r in ok):.1f}) | {med(r['return_wall'] for r in ok):.2f} | {base:.2f} "
              f"| {up / base:.2f}x | {max(r['error_cm'] for r in ok):.1f} cm / {max(r['error_deg'] for r in ok):.1f}° "
              f"| {sum(r['escapes'] for r in ok)} | {sum(r['collisions'] for r in ok)} "
              f"| {'yes' if all(r['ready'] for r in ok) else 'NO'} |")


if __name__ == "__main__":
    main()
