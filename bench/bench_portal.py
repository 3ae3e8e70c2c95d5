"""Benchmark: the remote-access portal — submission → verdict latency, jobs per hour, and job-status API throughput.

Run: ``.venv/bin/python bench/bench_portal.py [--jobs 3] [--seconds 10]`` (prints markdown tables).

1. **Pipeline** (in this process: service, verification workers on a local pool of 2 processes, the arena
   runner on the simulated arena in ``--fast`` mode, i.e. as fast as it computes): ``--jobs`` jobs of 12
   robots and 30 s (a rendezvous script), submitted at once. Per job: submission → verdict (queued →
   verifying → approved, verification with the server's default 4 runs each without and with the
   barrier), the arena's setup (sandbox boot until the first tick), the run itself, and the
   ending (closing the recording, CSV and HTML exports). Jobs per hour: measured (``--fast``) and,
   for the real-time arena, ``3600 / (30 s + setup + ending)`` — the arena is the bottleneck as long
   as verification of the next job finishes within a run, which the table shows. The exports (CSV, HTML
   replay, video) are written in the background and do not hold the arena.
0. **Gap between jobs** (``arena_gap``): the arena's idle time from one job's last Frame to the next job's
   first, with the exports on the arena thread (the old way, emulated in this process) and in the background.
2. **API**: ``swarmdeck server`` in its own process (real uvicorn on loopback); 50 concurrent
   clients (one ``httpx.AsyncClient`` each, keep-alive) for ``--seconds`` s against
   ``GET /api/jobs/{id}`` (Bearer token: token lookup, job row, queue position) and, in the same run,
   the static ``GET /api/health`` as the baseline. Requests/s and latency percentiles (wall clock:
   they include the load of the machine and the clients' own CPU on the same 2 cores), and the
   server process's CPU time per request (``/proc``), whose inverse is what one server core can
   serve, robust to other processes. Targets (issue 16): ≥ 500 requests/s, p99 ≤ 50 ms.
"""
from __future__ import annotations

import argparse
import asyncio
import json
import os
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import httpx

RENDEZVOUS = """
def experiment(arena):
    while True:
        p = arena.positions()
        arena.set_velocities(-0.5 * (p - p.mean(axis=0)))
        arena.step()
"""
CLI = harness.swarmdeck_cli()


def pipeline(n_jobs: int, workdir: Path) -> list[dict]:
    from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
    from swarmdeck.console.portal.service import PortalConfig, PortalService
    from swarmdeck.console.portal.states import FINAL, JobState
    from swarmdeck.console.portal.workers import VerificationWorkers
    from swarmdeck.console.sandbox.executors import LocalPoolExecutor

    service = PortalService(PortalConfig(data=workdir / "pipeline"))
    user, _ = service.accounts.add_user("bench", "researcher")
    workers = VerificationWorkers(service, LocalPoolExecutor(2), poll_s=0.05).start()
    runner = ArenaRunner(service, ArenaSettings(fleet=12, fast=True, seed=1), poll_s=0.05).start()
    service.arena = runner
    marks: dict[int, dict[str, float]] = {}
    t0 = time.monotonic()
    ids = []
    for k in range(n_jobs):
        job = service.submit(user, "rendezvous.py", RENDEZVOUS.encode(),
                             json.dumps({"name": f"bench {k}", "robots": 12, "duration": 30.0}))
        ids.append(job.id)
        marks[job.id] = {"submitted": time.monotonic()}
    while True:
        states = {jid: service.job_state(jid) for jid in ids}
        now = time.monotonic()
        for jid, state in states.items():
            marks[jid].setdefault(state, now)
        if all(s in FINAL for s in states.values()):
            break
        time.sleep(0.01)
    total = time.monotonic() - t0
    workers.stop()
    runner.exports.wait_idle(900)  # the exports (background) of the last jobs, for their exports_s
    runner.stop()
    rows = []
    for jid in ids:
        job = service.job(user, jid)
        m = marks[jid]
        verdict_at = min(t for state, t in m.items() if state not in ("submitted",
                                                                       JobState.AWAITING_VERIFICATION,
                                                                       JobState.VERIFYING))
        run = json.loads((service.job_dir(jid) / "run.json").read_text())
        rows.append({"id": jid, "state": job.state, "verdict": job.verdict,
                     "verdict_s": verdict_at - m["submitted"],
                     "verifying_s": verdict_at - m.get(JobState.VERIFYING, verdict_at),
                     "setup_s": m.get(JobState.RUNNING, now) - m.get(JobState.SETTING_UP, now),
                     "run_and_end_s": job.ended - job.started - (m.get(JobState.RUNNING, now) - m.get(JobState.SETTING_UP, now)),
                     "exports_s": run.get("exports_s", 0.0), "ticks": run.get("ticks")})
    service.close()
    print(f"\npipeline: {n_jobs} jobs in {total:.1f} s wall ({3600 * n_jobs / total:.0f} jobs/hour, --fast)")
    return rows


def arena_gap(n_jobs: int, workdir: Path) -> dict[str, dict]:
    """The arena's idle time between two jobs: the first Frame of job k+1 minus the last Frame of job k (wall s),
    ``n_jobs`` verified 12-robot 30 s jobs back to back on the in-process runner (``--fast``, the fleet's set-up
    and return included), twice in this process: **before** — the exports (CSV + HTML replay) written on the
    arena thread before the next job, as the runner did until 2026-11-23 — and **after** — every export
    (CSV + HTML replay + MP4 video) handed to the background exporter."""
    from swarmdeck.console.portal.exports import JobExports
    from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
    from swarmdeck.console.portal.service import PortalConfig, PortalService
    from swarmdeck.console.portal.states import FINAL, JobState

    out = {}
    for mode in ("before", "after"):
        service = PortalService(PortalConfig(data=workdir / f"gap-{mode}"))
        user, _ = service.accounts.add_user("bench", "researcher")
        runner = ArenaRunner(service, ArenaSettings(fleet=12, fast=True, seed=1), poll_s=0.05)
        if mode == "before":  # the arena thread waits for the CSV and the replay, as it used to
            blocking = JobExports(service, video=False)
            runner.exports = blocking
            submit = blocking.submit
            blocking.submit = lambda job_id, submit=submit, blocking=blocking: (submit(job_id), blocking.wait_idle(600))  # type: ignore[method-assign]
        frames: dict[int, list[float]] = {}

        def seen(frame, runner=runner, frames=frames) -> None:
            job = runner.current_job
            if job is not None:
                times = frames.setdefault(job, [time.monotonic(), 0.0])
                times[1] = time.monotonic()

        runner.frame_listeners.append(seen)
        ids = []
        for k in range(n_jobs):
            job = service.submit(user, "rendezvous.py", RENDEZVOUS.encode(),
                                 json.dumps({"name": f"gap {k}", "robots": 12, "duration": 30.0}))
            with service.db.transaction() as tx:
                for state in (JobState.VERIFYING, JobState.AWAITING_APPROVAL, JobState.IN_ARENA_QUEUE):
                    service.db.transition(tx, job.id, state, **({"verdict": "accepted"}
                                                                if state == JobState.AWAITING_APPROVAL else {}))
            ids.append(job.id)
        service.notify()
        runner.start()
        while not all(service.job_state(j) in FINAL for j in ids):
            time.sleep(0.05)
        runner.exports.wait_idle(900)
        runner.stop()
        gaps = [frames[b][0] - frames[a][1] for a, b in zip(ids, ids[1:])]
        runs = [json.loads((service.job_dir(j) / "run.json").read_text()) for j in ids]
        out[mode] = {"gaps": gaps, "states": [service.job_state(j) for j in ids],
                     "exports_s": [r.get("exports_s") for r in runs],
                     "exports": [service.job(user, j).exports for j in ids]}
        service.close()
    return out


def _cpu_s(pid: int) -> float:
    """User + system CPU seconds of process ``pid`` so far (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


async def _clients(url: str, path: str, token: str, clients: int, seconds: float) -> tuple[int, list[float], int]:
    latencies: list[float] = []
    errors = 0
    stop = time.monotonic() + seconds
    limits = httpx.Limits(max_connections=1, max_keepalive_connections=1)

    async def one() -> None:
        nonlocal errors
        async with httpx.AsyncClient(base_url=url, headers={"Authorization": f"Bearer {token}"}, limits=limits,
                                     timeout=30) as c:
            while time.monotonic() < stop:
                t = time.perf_counter()
                r = await c.get(path)
                latencies.append(time.perf_counter() - t)
                if r.status_code != 200:
                    errors += 1

    await asyncio.gather(*(one() for _ in range(clients)))
    return len(latencies), latencies, errors


def api(workdir: Path, seconds: float, clients: int = 50) -> list[dict]:
    data = workdir / "api"
    out = subprocess.run([*CLI, "users", "add", "bench", "--role", "researcher", "--data", str(data)],
                         capture_output=True, text=True, check=True).stdout
    token = out.strip().splitlines()[-1]
    server = subprocess.Popen([*CLI, "server", "--data", str(data), "--port", "0", "--fast"],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        url = ""
        for line in server.stdout:
            if line.startswith("swarmdeck server: http://"):
                url = line.split()[2]
                break
        with httpx.Client(base_url=url, headers={"Authorization": f"Bearer {token}"}) as c:
            r = c.post("/api/jobs", files={"script": ("x.py", b"x = 1\n")},
                       data={"manifest": json.dumps({"name": "status", "robots": 2, "duration": 1})})
            jid = r.json()["id"]
        rows = []
        for name, path in (("static /api/health (baseline)", "/api/health"), ("job status /api/jobs/{id}",
                                                                               f"/api/jobs/{jid}")):
            asyncio.run(_clients(url, path, token, clients, 1.0))  # warm-up
            t, cpu0, own0 = time.monotonic(), _cpu_s(server.pid), time.process_time()
            n, lat, errors = asyncio.run(_clients(url, path, token, clients, seconds))
            wall, cpu, own = time.monotonic() - t, _cpu_s(server.pid) - cpu0, time.process_time() - own0
            lat.sort()
            rows.append({"endpoint": name, "requests": n, "errors": errors, "rps": n / wall,
                         "p50_ms": 1e3 * statistics.median(lat), "p99_ms": 1e3 * lat[int(0.99 * (len(lat) - 1))],
                         "server_cpu_ms": 1e3 * cpu / n, "client_cpu_ms": 1e3 * own / n})
        return rows
    finally:
        server.terminate()
        server.wait(timeout=30)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--jobs", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--gap-jobs", type=int, default=4, help="jobs per mode for the gap between jobs")
    parser.add_argument("--only", choices=("api", "pipeline", "gap"), default=None, help="run one part")
    args = parser.parse_args()
    print(harness.machine())
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        if args.only in (None, "gap"):
            gap = arena_gap(args.gap_jobs, work)
            base = statistics.median(gap["before"]["gaps"])
            print("\n| exports | gaps between jobs, s | median s | ratio to before | jobs' states | exports s "
                  "(each job) | exports |")
            print("| --- | --- | ---: | ---: | --- | --- | --- |")
            for mode, what in (("before", "on the arena thread (CSV + replay)"),
                               ("after", "background process (CSV + replay + video)")):
                g = gap[mode]
                print(f"| {what} | {', '.join(f'{x:.2f}' for x in g['gaps'])} | {statistics.median(g['gaps']):.2f} "
                      f"| {statistics.median(g['gaps']) / base:.2f} | {', '.join(g['states'])} | "
                      f"{', '.join(f'{x:.1f}' for x in g['exports_s'])} | {', '.join(map(str, g['exports']))} |")
            if args.only:
                return
        rows = api(work, args.seconds) if args.only in (None, "api") else []
        print("\n| endpoint | requests/s (wall) | p50 ms | p99 ms | errors | server CPU ms/request | "
              "one server core's capacity, requests/s | client CPU ms/request | capacity ratio to baseline |")
        print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
        for r in rows:
            print(f"| {r['endpoint']} | {r['rps']:.0f} | {r['p50_ms']:.1f} | {r['p99_ms']:.1f} | {r['errors']} | "
                  f"{r['server_cpu_ms']:.2f} | {1e3 / r['server_cpu_ms']:.0f} | {r['client_cpu_ms']:.2f} | "
                  f"{rows[0]['server_cpu_ms'] / r['server_cpu_ms']:.2f} |")
        if args.only == "api":
            return
        jobs = pipeline(args.jobs, work)
        print("\n| job | verdict | submission → verdict s | of which verifying s | setup s | run and ending s (--fast) "
              "| exports s (background: CSV + HTML replay + video) |")
        print("| ---: | --- | ---: | ---: | ---: | ---: | ---: |")
        for j in jobs:
            print(f"| {j['id']} | {j['verdict']} | {j['verdict_s']:.1f} | {j['verifying_s']:.1f} | {j['setup_s']:.2f} "
                  f"| {j['run_and_end_s']:.1f} | {j['exports_s']:.1f} |")
        setup = statistics.median(j["setup_s"] for j in jobs)
        exports = statistics.median(j["exports_s"] for j in jobs)
        verifying = statistics.median(j["verifying_s"] for j in jobs)
        print(f"\nmedian verification {verifying:.1f} s per job; median setup {setup:.2f} s, exports {exports:.1f} s "
              f"(in the background); real-time arena: {3600 / (30 + setup):.0f} jobs/hour (30 s runs + setup; "
              f"while verification keeps up: {verifying:.1f} s per job on the pool)")


if __name__ == "__main__":
    main()
