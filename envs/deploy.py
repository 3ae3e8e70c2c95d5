"""A trained policy driving an :class:`~swarmdeck.devices.Arena`: what the experiment ``swarmdeck train`` writes runs.

:func:`drive` observes the arena as the policy's scenario does in training (``Scenario.observe`` on a
:class:`~swarmdeck.envs.scenario.View` of the arena's poses, clipped to the scenario's observation bounds), takes the
policy's action and holds it for the scenario's ``hold`` ticks — velocity actions through
``arena.set_velocities``, goal and move actions through ``arena.set_goals`` (the go-to-goal training uses) — until
the arena's duration is over or the scenario's episode ends. Every command passes the arena's safety pipeline
(the barrier): on the portal, the run is the arena's, inside the barrier, with the script in the sandbox.

Only numpy and swarmdeck are imported (no gymnasium, no torch): it runs in the lab's script environment.
"""
from __future__ import annotations

import re
from typing import Any

import numpy as np

from swarmdeck.envs.policy import Policy
from swarmdeck.envs.scenario import Scenario, View, goal_points
from swarmdeck.envs.scenarios import make_scenario

#: Seconds a run lasts when neither the arena nor the call gives a duration.
DEFAULT_DURATION = 30.0


def scenario_for(policy: Policy, n_robots: int, bounds: Any = None) -> Scenario:
    """The policy's scenario for ``n_robots`` robots on the floor ``bounds`` (None: the scenario's own); ValueError
    when its observation is not the size the policy takes."""
    args = {**policy.scenario_args, "n_agents": int(n_robots)}
    if bounds is not None:
        args["bounds"] = bounds
    scenario = make_scenario(policy.scenario, **args)
    if scenario.obs_size != policy.obs_size:
        raise ValueError(f"the policy takes observations of {policy.obs_size} numbers; scenario {policy.scenario!r} "
                         f"with {n_robots} robots gives {scenario.obs_size} (train it for this many robots)")
    if scenario.actions.kind != policy.action:
        raise ValueError(f"the policy gives {policy.action} actions; scenario {policy.scenario!r} takes "
                         f"{scenario.actions.kind} actions")
    return scenario


def drive(arena: Any, policy: Policy, *, duration: float | None = None, seed: int = 0) -> dict[str, float]:
    """Run ``policy`` on ``arena`` (module docstring) for ``duration`` s (default: the arena's, else
    :data:`DEFAULT_DURATION`); ``seed`` draws the scenario's own state (e.g. MARBLER's prey). Returns the mean reward
    per agent and step, the steps taken and whether the scenario's episode ended."""
    scenario = scenario_for(policy, arena.n, arena.config.bounds)
    low, high = (np.asarray(b, dtype=np.float32) for b in scenario.observation_bounds())
    _, start = scenario.reset(np.random.default_rng(seed))  # the scenario's state; the poses are the arena's
    state = {k: np.asarray(v)[None] for k, v in start.items()}
    moves = policy.action == "moves"
    last: np.ndarray = np.full((1, arena.n), 4, dtype=np.int64) if moves else np.zeros((1, arena.n, 2))
    end = duration if duration is not None else (arena.duration if arena.duration is not None else DEFAULT_DURATION)
    steps, total, ended = 0, 0.0, False

    def view() -> View:
        return View(arena.poses()[None], arena.positions()[None], state, last, np.array([steps]), scenario.bounds)

    while arena.time < end - 1e-9:
        obs = np.clip(np.asarray(scenario.observe(view()), dtype=np.float32), low, high)[0]
        action = policy.act(obs)
        if policy.action == "velocity":
            arena.set_velocities(action)
        else:
            arena.set_goals(goal_points(scenario.actions, action, arena.poses()[:, :2], scenario.bounds))
        for _ in range(scenario.actions.hold):
            if arena.time >= end - 1e-9:
                break
            arena.step()
        last = action[None]
        steps += 1
        rewards, state = scenario.reward(view())
        total += float(np.mean(rewards))
        if bool(np.asarray(scenario.terminated(view()))[0]):
            ended = True
            break
    arena.stop()
    return {"policy steps": float(steps), "mean reward per agent and step": total / max(steps, 1),
            "episode ended": float(ended)}


def experiment_script(policy: Policy, robots: int, duration: float) -> str:
    """The experiment script ``swarmdeck train`` writes beside ``policy.npz`` (the bundle's ``main.py``): it loads the
    policy file from its own folder (inside the sandbox too) and :func:`drive` s the arena with it; ``robots`` and
    ``duration`` (s) are its defaults as ``python main.py`` runs it (``swarmdeck run --robots/--duration`` and the
    portal's manifest override them)."""
    trained = policy.meta.get("trained", {})
    how = ", ".join(f"{k} {v}" for k, v in trained.items() if isinstance(v, (str, int, float)))
    how = re.sub(r"[^\w .,:=+-]", "", how)[:200]  # the file's words go into a docstring: no quotes, no newlines
    scenario = re.sub(r"[^\w-]", "", policy.scenario)[:60]
    return f'''"""A policy trained by `swarmdeck train` on the {scenario} scenario ({how}) driving the arena.

The policy is policy.npz beside this file: plain numpy weights, checked when loaded (swarmdeck.envs.policy).
Every command passes the arena's safety barrier.

    swarmdeck run main.py                      # in simulation, on this machine
    swarmdeck run . --sandbox                  # as the portal runs it: this folder in the jail
    swarmdeck submit ../FOLDER.zip             # onto the lab's portal: the archive beside this folder
"""
from pathlib import Path

from swarmdeck.devices import Arena
from swarmdeck.envs.deploy import drive
from swarmdeck.envs.policy import load_policy

POLICY = Path(__file__).with_name("policy.npz")


def experiment(arena: Arena) -> dict:
    """Drive ``arena`` with the trained policy until its duration is over; the mean reward per agent and step."""
    return drive(arena, load_policy(POLICY))


if __name__ == "__main__":
    arena = Arena({int(robots)}, duration={float(duration)!r})
    results = experiment(arena)
    arena.call_at_scripts_end()
    for name, value in results.items():
        print(f"{{name}}: {{value:.4f}}")
'''
