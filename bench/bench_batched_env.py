"""Batched learning environment (issue 27 item 3): robot-steps per second at (E, N) = (64, 10), (16, 100), (1, 1000).

Run: ``.venv/bin/python bench/bench_batched_env.py`` (prints a markdown table; ~3 min on the shared VM).
Optional: ``--vmas PYTHON`` times VMAS (``vmas.make_env("navigation", device="cpu")``, E envs × N agents, random
actions) in that interpreter (VMAS needs torch, which swarmdeck does not install).

Timing: process CPU time (``time.process_time``; robust to the other processes on this loaded machine), blocks
of ticks, median and worst block per tick; everything in one process, same poses and commands (each robot at
0.15 m/s towards its swarm's centre at the start plus noise, eight such arrays made before the timing and cycled,
so the robots crowd the centre and the barrier works). Columns, per tick of E·N robots:

* numpy unicycle: the plain step x += v cos θ dt, y += v sin θ dt, θ += ω dt on (E·N,) arrays — the floor;
* ``BatchedSwarm.tick``: the arena pipeline (certify: look-ahead map, wheel limits), the distributed barrier
  (on) and the exact unicycle step;
* ``BatchedEnv.step``: the Rendezvous scenario, tick + observations (3 neighbours) + rewards;
* separate envs: E ``parallel_env(task="rendezvous", barrier="distributed")`` stepped one after the other.
"""
from __future__ import annotations

import argparse
import itertools
import json
import os
import statistics
import subprocess
import sys
import time
from collections.abc import Iterator

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np

from swarmdeck.devices import random_initial_poses
from swarmdeck.envs import BatchedEnv, parallel_env, scenarios
from swarmdeck.envs.batched_swarm import BatchedSwarm

CASES = ((64, 10, (-1.6, 1.6, -1.0, 1.0)), (16, 100, (-4.0, 4.0, -2.5, 2.5)), (1, 1000, (-8.0, 8.0, -5.0, 5.0)))


def timed(fn, blocks: int, per: int) -> tuple[float, float]:
    """(median, worst) CPU seconds per call over ``blocks`` blocks of ``per`` calls (after one warm-up call)."""
    fn()
    out = []
    for _ in range(blocks):
        t = time.process_time()
        for _ in range(per):
            fn()
        out.append((time.process_time() - t) / per)
    return statistics.median(out), max(out)


def towards_centre(points: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    d = points.mean(axis=-2, keepdims=True) - points
    u = 0.15 * d / np.maximum(np.linalg.norm(d, axis=-1, keepdims=True), 1e-9)
    return u + rng.normal(0, 0.03, u.shape)


def commands(points: np.ndarray, rng: np.random.Generator, dtype: type = float) -> Iterator[np.ndarray]:
    """Eight command arrays towards each swarm's centre at the start (plus noise), cycled: made before the timing,
    so the figures are the simulator's, not the command generator's (the robots crowd the centre: the barrier
    works)."""
    return itertools.cycle([towards_centre(points, rng).astype(dtype) for _ in range(8)])


def numpy_unicycle(poses: np.ndarray, v: np.ndarray, w: np.ndarray, dt: float) -> np.ndarray:
    out = np.empty_like(poses)
    out[:, 0] = poses[:, 0] + v * np.cos(poses[:, 2]) * dt
    out[:, 1] = poses[:, 1] + v * np.sin(poses[:, 2]) * dt
    out[:, 2] = poses[:, 2] + w * dt
    return out


def vmas_rate(python: str, e: int, n: int, timeout: float = 400.0) -> str:
    code = f"""
import time, statistics, torch, vmas, json
torch.set_num_threads(1)
env = vmas.make_env("navigation", num_envs={e}, device="cpu", n_agents={n}, continuous_actions=True, seed=0)
env.reset()
acts = lambda: [torch.rand({e}, 2) * 2 - 1 for _ in range({n})]
env.step(acts())
out = []
blocks, per = (5, 5) if {e} * {n} < 1000 else (3, 2)
for _ in range(blocks):
    t = time.process_time()
    for _ in range(per):
        env.step(acts())
    out.append((time.process_time() - t) / per)
print(json.dumps([statistics.median(out), max(out)]))
"""
    try:
        res = subprocess.run([python, "-c", code], capture_output=True, text=True, timeout=timeout)
        med, worst = json.loads(res.stdout.strip().splitlines()[-1])
    except subprocess.TimeoutExpired:
        return f"did not finish in {timeout:.0f} s"
    except Exception as exc:  # noqa: BLE001 - report, never crash the bench
        return f"n/a ({type(exc).__name__})"
    return f"{e * n / med:,.0f} (worst {e * n / worst:,.0f})"


def row(e: int, n: int, bounds: tuple[float, float, float, float], vmas: str | None, vmas_timeout: float) -> str:
    rng = np.random.default_rng(0)
    poses = np.stack([random_initial_poses(n, bounds, rng=rng) for _ in range(e)])
    blocks, per = (7, 20) if e * n <= 1000 else (7, 10)
    cells = []
    flat = poses.reshape(-1, 3)
    v, w = rng.uniform(0, 0.2, e * n), rng.uniform(-1, 1, e * n)
    base, base_worst = timed(lambda: numpy_unicycle(flat, v, w, 0.033), blocks * 4, per * 20)
    cells.append(f"{e * n / base:,.0f}")
    for safety in (False, True):
        sim = BatchedSwarm(e, n, bounds=bounds, safety=safety)
        sim.set_poses(poses)

        acts = commands(sim.points(), rng)

        def tick(sim=sim, acts=acts):
            sim.tick(next(acts), check=False)
        med, worst = timed(tick, blocks, per)
        cells.append(f"{e * n / med:,.0f} (worst {e * n / worst:,.0f}; {med / base:.0f}x numpy)")
    for safety in (False, True):
        env = BatchedEnv(scenarios.Rendezvous(n_agents=n, bounds=bounds, max_steps=10**6), e, safety=safety)
        env.reset(seed=0)

        acts = commands(env.sim.points(), rng, np.float32)

        def step(env=env, acts=acts):
            env.step(next(acts))
        med, worst = timed(step, blocks, per)
        cells.append(f"{e * n / med:,.0f} (worst {e * n / worst:,.0f})")
    singles = [parallel_env(n_robots=n, task="rendezvous", barrier="distributed", bounds=bounds, max_steps=10**6)
               for _ in range(e)]
    for k, s in enumerate(singles):
        s.reset(seed=k)

    def separate():
        for s in singles:
            u = towards_centre(s.arena.positions(), rng).astype(np.float32)
            s.step({a: u[i] for i, a in enumerate(s.possible_agents)})
    med, _ = timed(separate, 3, 1)
    batched_on = float(cells[-1].split(" ")[0].replace(",", ""))
    cells.append(f"{e * n / med:,.0f} (batched {batched_on / (e * n / med):.0f}x)")
    cells.append(vmas_rate(vmas, e, n, vmas_timeout) if vmas else "not installed")
    return f"| ({e}, {n}) | " + " | ".join(cells) + " |"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vmas", metavar="PYTHON", help="an interpreter with vmas and torch installed")
    ap.add_argument("--vmas-timeout", type=float, default=400.0, metavar="S",
                    help="seconds VMAS may take per row (make_env, reset, the timed steps; default 400)")
    args = ap.parse_args()
    print(harness.machine())
    print("| (E, N) | numpy unicycle | BatchedSwarm.tick, barrier off | BatchedSwarm.tick, barrier on | "
          "BatchedEnv.step, off | BatchedEnv.step, on | E separate envs, on | VMAS navigation (CPU) |")
    print("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for e, n, bounds in CASES:
        print(row(e, n, bounds, args.vmas, args.vmas_timeout), flush=True)
    print("\nrobot-steps per CPU second, median block (worst block); Python", sys.version.split()[0],
          "numpy", np.__version__, "; load average", " ".join(f"{x:.1f}" for x in os.getloadavg()))


if __name__ == "__main__":
    main()
