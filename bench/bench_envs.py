"""Learning-environment benchmarks (issue 19): env steps per second at N = 10 and 100, safety filter on.

Run: ``.venv/bin/python bench/bench_envs.py`` (prints a markdown table; ~1 min).

Per N, in one process, median over blocks of steps (process CPU time, robust to the other
processes on this shared VM): the bare simulator step (``SimulatedArena.step``, the baseline),
``Arena.step`` with the barrier filter (what every env action goes through), and
``SwarmParallelEnv.step`` for the rendezvous and coverage tasks (actions: each robot at 0.15 m/s
towards the swarm's centre, so the filter works; observations with 3 neighbours; rewards).
"""
from __future__ import annotations

import sys
import time

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np

import swarmdeck.envs as envs
from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.devices import Arena, ArenaConfig, SimulatedArena, random_initial_poses


def blocks(fn, n_blocks: int = 7, per: int = 10) -> float:
    """Median process-CPU seconds per call of ``fn``, over ``n_blocks`` blocks of ``per`` calls."""
    def block() -> None:
        for _ in range(per):
            fn()
    return harness.measure(block, n_blocks, clock="cpu").median / per


def towards_centre(points: np.ndarray) -> np.ndarray:
    d = points.mean(axis=0) - points
    return 0.15 * d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-9)


def row(n: int) -> str:
    bounds = DEFAULT_BOUNDS if n <= 20 else (-4.0, 4.0, -2.5, 2.5)
    poses = random_initial_poses(n, bounds, rng=0)
    sim = SimulatedArena(n, poses, config=ArenaConfig(bounds=bounds))
    v, w = np.full(n, 0.05), np.full(n, 0.2)
    bare = blocks(lambda: sim.step(v, w), per=50)
    arena = Arena(initial_conditions=poses, config=ArenaConfig(bounds=bounds), safety=True)

    def arena_step():
        arena.set_velocities(towards_centre(arena.positions()))
        arena.step()
    filt = blocks(arena_step)
    res = {}
    for task in ("rendezvous", "coverage"):
        env = envs.parallel_env(n_robots=n, task=task, bounds=bounds, max_steps=10**6)
        env.reset(seed=0)

        def env_step(env=env):
            u = towards_centre(env.arena.positions()).astype(np.float32)
            env.step({a: u[i] for i, a in enumerate(env.possible_agents)})
        res[task] = blocks(env_step, n_blocks=5 if task == "coverage" else 7)
    return (f"| {n} | {bare * 1e3:.3f} | {filt * 1e3:.2f} ({filt / bare:.0f}x) | "
            f"{res['rendezvous'] * 1e3:.2f} ({res['rendezvous'] / bare:.0f}x) | {1 / res['rendezvous']:.0f} | "
            f"{res['coverage'] * 1e3:.2f} ({res['coverage'] / bare:.0f}x) | {1 / res['coverage']:.0f} |")


def main() -> int:
    print(f"env benchmarks — {time.strftime('%Y-%m-%d')}, {harness.machine()}\n")
    print("| N | bare simulator step (ms) | Arena.step, filter on (ms, ratio) | env step, rendezvous (ms, ratio) | "
          "steps/s | env step, coverage (ms, ratio) | steps/s |")
    print("| ---: | ---: | ---: | ---: | ---: | ---: | ---: |")
    for n in (10, 100):
        print(row(n), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
