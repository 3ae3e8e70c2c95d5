"""`swarmdeck train`'s cost and what it learns: PPO (Stable-Baselines3) on a shipped scenario, then the trained
numpy policy against a zero action and random actions on the same seeded episodes of the batched environment.

    .venv/bin/python bench/bench_train.py [--scenario rendezvous] [--steps 50000] [--envs 16] [--robots 4]

Prints the import time of torch + Stable-Baselines3, the training's process CPU time and agent-steps per CPU second,
and the mean reward per agent and step of each policy (higher is better) over ``--episodes`` episodes.
"""
from __future__ import annotations

import argparse
import time

import harness  # pins BLAS first
import numpy as np


def evaluate(scenario, act, episodes: int, seed: int) -> float:
    """Mean reward per agent and step of ``act(obs (E·N, D)) -> actions`` over ``episodes`` swarms' first episode."""
    from swarmdeck.envs.batched import BatchedEnv

    env = BatchedEnv(scenario, episodes)
    obs, _ = env.reset(seed=seed)
    total, count = 0.0, 0
    live = np.ones(episodes, dtype=bool)
    for _ in range(scenario.max_steps):
        e, n, d = obs.shape
        a = act(obs.reshape(e * n, d))
        a = a.reshape(e, n) if scenario.actions.kind == "moves" else a.reshape(e, n, 2)
        obs, rew, term, trunc, _ = env.step(a)
        total += float(rew[live].sum())
        count += int(live.sum()) * n
        live &= ~(term | trunc)
        if not live.any():
            break
    return total / max(count, 1)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default="rendezvous")
    ap.add_argument("--steps", type=int, default=50000)
    ap.add_argument("--envs", type=int, default=16)
    ap.add_argument("--robots", type=int, default=4)
    ap.add_argument("--episodes", type=int, default=16)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    print(harness.machine())
    t0, c0 = time.perf_counter(), time.process_time()
    from swarmdeck.envs.train import train  # torch + Stable-Baselines3
    print(f"import torch + stable-baselines3: {time.perf_counter() - t0:.1f} s wall, {time.process_time() - c0:.1f} s CPU")
    from swarmdeck.envs.scenarios import make_scenario

    c0 = time.process_time()
    policy = train(args.scenario, steps=args.steps, n_agents=args.robots, n_envs=args.envs, seed=args.seed)
    cpu = time.process_time() - c0
    steps = policy.meta["trained"]["steps"]
    print(f"training {args.scenario}, {args.envs} swarms x {args.robots} robots, {steps} agent-steps: {cpu:.1f} s CPU, "
          f"{steps / cpu:,.0f} agent-steps per CPU second")
    sc = make_scenario(args.scenario, n_agents=args.robots)
    rng = np.random.default_rng(1)
    moves = sc.actions.kind == "moves"

    def zero(obs):
        return np.full(len(obs), 4) if moves else np.zeros((len(obs), 2))

    def rand(obs):
        return rng.integers(0, 5, len(obs)) if moves else rng.uniform(policy.action_low, policy.action_high, (len(obs), 2))

    for name, act in (("trained", policy.act), ("zero action", zero), ("random", rand)):
        r = evaluate(sc, act, args.episodes, seed=10_000 + args.seed)
        print(f"  {name:12s} mean reward per agent and step: {r:+.4f}")


if __name__ == "__main__":
    main()
