"""Stepping swarmdeck's learning environment with a random and a scripted policy (no training).

The PettingZoo environment ``swarmdeck.envs.parallel_env`` has one agent per robot; every
action passes the barrier-certificate safety filter, and ``infos[agent]["filter_change"]``
says by how much (m/s). Needs the extra: ``pip install 'swarmdeck[rl]'``.

    .venv/bin/python examples/learning_env.py --task coverage --robots 10
    .venv/bin/python examples/learning_env.py --task formation --record episodes/   # then: swarmdeck play episodes/episode-001.mcap

Scripted policies: coverage — Lloyd's law towards the centroid of the robot's Voronoi cell
(``env.moments.centroids``, from the last step's reward computation); formation — straight to
the robot's slot; rendezvous — towards the swarm's centre.
"""
from __future__ import annotations

import argparse

import numpy as np

import swarmdeck.envs as envs


def scripted(env: envs.SwarmParallelEnv) -> dict[str, np.ndarray]:
    """One action per agent: the task's textbook controller, at most 0.2 m/s per axis."""
    p = env.arena.positions()
    if env.config.task == "coverage":
        target = env.moments.centroids if env.moments is not None else p
    elif env.config.task == "formation":
        target = env.slots
    else:
        target = np.broadcast_to(p.mean(axis=0), p.shape)
    u = np.clip(1.0 * (target - p), -0.2, 0.2).astype(np.float32)
    return {a: u[i] for i, a in enumerate(env.possible_agents)}


def run(env, policy: str, seed: int) -> tuple[float, float, float]:
    """One episode: (mean reward per agent and step, mean filter change m/s, share of actions the filter changed)."""
    env.reset(seed=seed)
    swarm = env.unwrapped
    rewards: list[float] = []
    changes: list[float] = []
    while env.agents:
        acts = scripted(swarm) if policy == "scripted" else {a: env.action_space(a).sample() for a in env.agents}
        _, r, _, _, infos = env.step(acts)
        rewards.append(np.mean(list(r.values())))
        changes.extend(i["filter_change"] for i in infos.values())
    ch = np.asarray(changes)
    return float(np.mean(rewards)), float(ch.mean()), float(np.mean(ch > 1e-9))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--task", choices=envs.TASKS, default="coverage")
    ap.add_argument("--robots", type=int, default=8)
    ap.add_argument("--steps", type=int, default=200, help="steps per episode (0.033 s each)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--record", metavar="DIR", help="record each episode to DIR/episode-NNN.mcap")
    args = ap.parse_args(argv)
    env = envs.parallel_env(n_robots=args.robots, task=args.task, max_steps=args.steps)
    if args.record:
        from swarmdeck.console.recording.episodes import record_episodes

        env = record_episodes(env, args.record)
    for policy in ("random", "scripted"):
        reward, change, share = run(env, policy, args.seed)
        print(f"{args.task:10s} {policy:8s}  mean reward {reward:+.4f}  filter change {change:.4f} m/s "
              f"({100 * share:.0f} % of actions changed)")
    env.close()
    if args.record:
        print("recorded:", ", ".join(str(p) for p in env.paths))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
