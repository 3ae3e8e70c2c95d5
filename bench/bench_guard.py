"""Benchmark of the guard of a bypassed barrier (issue 24): its per-tick cost against the barrier's own, same process.

Run: ``.venv/bin/python bench/bench_guard.py [--ticks T]``.

Scenes: N robots on a jittered grid (``safety.scenes.grid_scene``), random headings, nominal look-ahead velocities
at 0.2 m/s whose directions drift every tick (a random walk of 0.3 rad per tick), closed loop (the robots move by
the certified commands, exact unicycle step). *dense*: grid pitch D_s + 0.018 m in the default 3.2 × 2.0 m arena
(pair rows bind on most ticks: the worst case; a real bypass is revoked at the first tick the barrier would
intervene by more than 0.1 m/s); *sparse*: pitch 0.45 m (the distance at which a pair row can start to bind) in an
arena of the same aspect sized for N (``safety.scenes.arena_for``).

Per tick, CPU time of this thread (``time.thread_time``; robust to other load on a shared VM) of

* **barrier**: ``devices.pipeline.certify`` with the full unicycle barrier — what every run pays (with the barrier
  on it is the whole safety stage; during a bypass the guard evaluates it in monitor mode);
* what the guard adds to it during a bypass (``devices.pipeline.certify_bypassed``):
  - **walls**: ``certify`` with the same filter without pair rows, solved only for the robots of active pair rows of
    the full barrier (the others' full answer is their walls-and-obstacles answer; nothing to solve on ticks where
    no pair row binds),
  - **assess**: the prediction over the next tick (exact arc) and ``safety.guard.assess`` (trip rules and brake from
    one k-d tree query);
* **brake**: after a revocation, ``devices.pipeline.brake`` on the barrier's commands every tick;
* **contacts**: ``ContactWatch.update`` (every run, bypassed or not; not part of the guard).

Medians and worst over the ticks (the first 5, the warm-up, left out); "binds": ticks on which a pair row was active.
"""
from __future__ import annotations

import argparse  # noqa: E402
import time  # noqa: E402

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np  # noqa: E402

from swarmdeck.console.runtime.contacts import ContactWatch  # noqa: E402
from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.core.constants import CONTROL_PERIOD
from swarmdeck.core.kinematics import GritsBotParams, lookahead_points, unicycle_step  # noqa: E402
from swarmdeck.devices.pipeline import _without_pairs, barrier_filter, brake, certify, next_points  # noqa: E402
from swarmdeck.safety import BarrierConfig  # noqa: E402
from swarmdeck.safety.guard import GuardConfig, assess  # noqa: E402
from swarmdeck.safety.scenes import arena_for, grid_scene  # noqa: E402

DT = CONTROL_PERIOD
DENSE_BOUNDS = DEFAULT_BOUNDS
SPARSE_PITCH = 0.45


def run(n: int, ticks: int, scene: str, seed: int = 0) -> tuple[dict[str, np.ndarray], float]:
    robot, guard = GritsBotParams(), GuardConfig()
    rng = np.random.default_rng(seed)
    if scene == "dense":
        bounds = DENSE_BOUNDS
        points, _ = grid_scene(n, rng, BarrierConfig(bounds=bounds))
    else:
        bounds = arena_for(n, SPARSE_PITCH)
        points, _ = grid_scene(n, rng, BarrierConfig(bounds=bounds), pitch=SPARSE_PITCH)
    heading = rng.uniform(-np.pi, np.pi, n)
    poses = np.column_stack((points[:, 0] - robot.lookahead * np.cos(heading),
                             points[:, 1] - robot.lookahead * np.sin(heading), heading))
    direction = rng.uniform(-np.pi, np.pi, n)
    full = barrier_filter(robot, bounds, DT)
    walls = barrier_filter(robot, bounds, DT, pairs=False)
    contacts = ContactWatch()
    ids = np.arange(n)
    seen = np.ones(n, dtype=bool)
    times: dict[str, list[float]] = {k: [] for k in ("barrier", "walls", "assess", "brake", "contacts")}
    binds = []
    clock = time.thread_time
    for tick in range(ticks):
        direction = direction + rng.normal(0.0, 0.3, n)
        nominal = 0.2 * np.column_stack((np.cos(direction), np.sin(direction)))
        t0 = clock()
        cert = certify(poses, nominal, robot, full)
        t1 = clock()
        bind = len(cert.diagnostics.active_pairs) > 0 or "soft" in cert.diagnostics.status
        kept = _without_pairs(cert, poses, nominal, robot, walls, seen, np.zeros((0, 2)))  # no fixed points
        t2 = clock()
        p0, p1 = lookahead_points(poses, robot.lookahead), next_points(poses, kept.v, kept.w, robot, DT)
        extra = np.linalg.norm(cert.safe - kept.safe, axis=1) if bind else np.zeros(n)
        verdict, _ = assess(guard, p0, p1, extra, np.zeros((0, 2)), cert.ok, cert.status)
        t3 = clock()
        braked, _ = brake(cert, poses, robot, DT, guard.guard_distance, seen=seen, obstacles=None)
        t4 = clock()
        contacts.update(tick, tick * DT, ids, poses, seen)
        t5 = clock()
        for key, a, b in zip(times, (t0, t1, t2, t3, t4), (t1, t2, t3, t4, t5)):
            times[key].append(b - a)
        binds.append(bind)
        assert verdict.closest >= 0 and braked.ok
        poses = unicycle_step(poses, braked.v, braked.w, DT)
    return {k: np.asarray(v[5:]) * 1e3 for k, v in times.items()}, float(np.mean(binds[5:]))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks", type=int, default=300)
    args = parser.parse_args()
    print(f"# {harness.machine()}, {args.ticks} ticks")
    print("| scene | N | binds | barrier ms median (worst) | walls ms median | assess ms median (worst) "
          "| guard during a bypass ms median (worst) | guard / barrier | brake after revocation ms median (worst) "
          "| brake / barrier | contacts ms median |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for scene in ("sparse", "dense"):
        for n in (20, 100):
            t, binds = run(n, args.ticks, scene)
            bypass = t["walls"] + t["assess"]
            med = {k: float(np.median(v)) for k, v in t.items()}
            print(f"| {scene} | {n} | {100 * binds:.0f} % | {med['barrier']:.3f} ({t['barrier'].max():.2f}) "
                  f"| {med['walls']:.3f} | {med['assess']:.3f} ({t['assess'].max():.2f}) "
                  f"| {np.median(bypass):.3f} ({bypass.max():.2f}) | {100 * np.median(bypass) / med['barrier']:.0f} % "
                  f"| {med['brake']:.3f} ({t['brake'].max():.2f}) | {100 * med['brake'] / med['barrier']:.0f} % "
                  f"| {med['contacts']:.3f} |")


if __name__ == "__main__":
    main()
