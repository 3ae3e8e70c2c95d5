"""MARBLER's PredatorCapturePrey and Warehouse as swarmdeck scenarios: rewards, state updates and observations equal
MARBLER's own code (tests/data/marbler, run in a child process on the rps facade) on the same seeded states; and in
the batched environment a collision or boundary violation ends that swarm's episode with MARBLER's −5."""
from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
from marbler_fixtures import DATA, marbler_env

from swarmdeck.core.kinematics import lookahead_points
from swarmdeck.envs import Actions, BatchedEnv, Scenario, View, scenarios

CHILD = r"""
import json, sys
from types import SimpleNamespace
import numpy as np
import yaml
from swarmdeck.devices.rps import rps_aliases

root = sys.argv[1]
with rps_aliases():
    from robotarium_gym.scenarios.PredatorCapturePrey.PredatorCapturePrey import PredatorCapturePrey
    from robotarium_gym.scenarios.PredatorCapturePrey.agent import Agent
    from robotarium_gym.scenarios.Warehouse.warehouse import Warehouse, Agent as WAgent

def args(name):
    with open(f"{root}/robotarium_gym/scenarios/{name}/config.yaml") as f:
        return SimpleNamespace(**yaml.safe_load(f))

words = {0: "left", 1: "right", 2: "up", 3: "down", 4: "no_action"}
out = []
for case in json.load(sys.stdin):
    poses = np.array(case["poses"]).T
    if case["scenario"] == "pcp":
        a = args("PredatorCapturePrey")
        env = PredatorCapturePrey.__new__(PredatorCapturePrey)
        env.args, env.num_robots, env.num_prey = a, a.predator + a.capture, a.num_prey
        env.action_id2w = words
        env.agents = [Agent(i, a.predator_radius, 0, words, False) for i in range(a.predator)]
        env.agents += [Agent(i + a.predator, 0, a.capture_radius, words, False) for i in range(a.capture)]
        env.agent_obs_dim = 4
        env.prey_loc = np.array(case["prey"])
        env.prey_sensed, env.prey_captured = list(case["sensed"]), list(case["captured"])
        env.agent_poses = poses
        env.state_space = env._generate_state_space()
        env._update_tracking_and_locations(case["actions"])
        new = env._generate_state_space()
        env.prey_locs = []
        obs = env.get_observations(new)
        rew = env.get_rewards(new)
        out.append({"reward": [rew] * env.num_robots, "obs": [np.asarray(o, float).tolist() for o in obs],
                    "state": [bool(x) for x in env.prey_sensed] + [bool(x) for x in env.prey_captured]})
    else:
        a = args("Warehouse")
        env = Warehouse.__new__(Warehouse)
        env.args, env.num_robots, env.agent_obs_dim, env.action_id2w = a, a.n_agents, 3, words
        env.agents = [WAgent(i, words, "Green" if i % 2 == 0 else "Red") for i in range(a.n_agents)]
        for ag, loaded in zip(env.agents, case["loaded"]):
            ag.loaded = loaded
        env.agent_poses = poses
        obs = env.get_observations()  # MARBLER's step observes, then rewards
        rew = env.get_rewards()
        out.append({"reward": [float(r) for r in rew], "obs": [np.asarray(o, float).tolist() for o in obs],
                    "state": [bool(ag.loaded) for ag in env.agents]})
json.dump(out, sys.stdout)
"""


def _cases(seed: int, count: int) -> list[dict]:
    rng = np.random.default_rng(seed)
    cases = []
    for k in range(count):
        if k % 2 == 0:
            poses = np.column_stack((rng.uniform(-1.4, 1.4, (4, 2)), rng.uniform(-np.pi, np.pi, 4)))
            near = poses[rng.integers(0, 4, 6), :2] + rng.normal(0, 0.3, (6, 2))  # prey often within reach
            sensed = rng.random(6) < 0.4
            cases.append({"scenario": "pcp", "poses": poses.tolist(), "prey": near.tolist(),
                          "sensed": sensed.tolist(), "captured": (sensed & (rng.random(6) < 0.3)).tolist(),
                          "actions": rng.choice(5, 4, p=[0.1, 0.1, 0.1, 0.1, 0.6]).tolist()})
        else:
            x = rng.choice([-1.3, 1.3, 0.0], 6) + rng.uniform(-0.25, 0.25, 6)  # in the zones and between
            poses = np.column_stack((x, rng.uniform(-0.9, 0.9, 6), rng.uniform(-np.pi, np.pi, 6)))
            cases.append({"scenario": "warehouse", "poses": poses.tolist(), "loaded": (rng.random(6) < 0.5).tolist()})
    return cases


def _view(poses, state, actions) -> View:
    p = np.asarray(poses)[None]
    return View(p, lookahead_points(p[0], 0.03)[None], state, np.asarray(actions)[None], np.zeros(1, np.int64),
                (-1.6, 1.6, -1.0, 1.0))


def test_rewards_and_observations_equal_marblers_on_the_same_seeded_states(tmp_path):
    cases = _cases(seed=2024, count=400)
    main = DATA / "marbler" / "robotarium_gym" / "main.py"
    child = subprocess.run([sys.executable, "-c", CHILD, str(DATA / "marbler")], input=json.dumps(cases),
                           env=marbler_env(main), capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert child.returncode == 0, child.stderr
    theirs = json.loads(child.stdout)
    pcp, wh = scenarios.PredatorCapturePrey(), scenarios.Warehouse()
    events = {"sensed": 0, "captured": 0, "loaded": 0, "unloaded": 0}
    for case, ref in zip(cases, theirs, strict=True):
        if case["scenario"] == "pcp":
            state = {"prey": np.array(case["prey"])[None], "sensed": np.array(case["sensed"])[None],
                     "captured": np.array(case["captured"])[None]}
            view = _view(case["poses"], state, case["actions"])
            reward, new = pcp.reward(view)
            obs = pcp.observe(_view(case["poses"], new, case["actions"]))
            mine_state = np.concatenate((new["sensed"][0], new["captured"][0])).tolist()
            events["sensed"] += int(new["sensed"].sum() - state["sensed"].sum())
            events["captured"] += int(new["captured"].sum() - state["captured"].sum())
        else:
            loaded = np.array(case["loaded"])[None]
            view = _view(case["poses"], {"loaded": loaded, "shown": loaded}, np.zeros((1, 6), np.int64))
            obs = wh.observe(view)
            reward, new = wh.reward(view)
            mine_state = new["loaded"][0].tolist()
            events["loaded"] += int((new["loaded"] & ~loaded).sum())
            events["unloaded"] += int((~new["loaded"] & loaded).sum())
        assert np.allclose(reward[0], ref["reward"], rtol=0, atol=1e-12), (case, ref["reward"], reward)
        assert mine_state == ref["state"], case
        assert np.array_equal(obs[0], np.asarray(ref["obs"], dtype=np.float32)), case
    assert min(events.values()) > 5, events  # every reward branch was taken


def test_a_collision_ends_the_swarms_episode_with_marblers_penalty():
    # two robots driven into each other with the barrier off: that swarm ends with −5 for everyone; the other goes on
    class Collide(Scenario):
        def reset(self, rng):
            return np.array([[-0.3, 0.0, 0.0], [0.3, 0.0, np.pi]]), {}

    sc = Collide(n_agents=2, actions=Actions("velocity", hold=10), violation_penalty=-5.0, max_steps=50)
    env = BatchedEnv(sc, 2, safety=False)
    env.reset(seed=0)
    act = np.zeros((2, 2, 2), np.float32)
    act[0] = [[0.2, 0.0], [-0.2, 0.0]]
    for _ in range(20):
        obs, rew, term, trunc, info = env.step(act)
        if term[0]:
            break
    assert term[0] and not term[1] and info["violation"][0] == "collision" and info["violation"][1] == ""
    assert np.array_equal(rew[0], [-5.0, -5.0]) and np.array_equal(rew[1], [0.0, 0.0])
    _, rew, term, _, info = env.step(act)  # next-step autoreset of swarm 0
    assert info["reset"][0] and not info["reset"][1] and rew[0].tolist() == [0.0, 0.0] and not term[0]
    # with the barrier on, the same commands never collide
    safe = BatchedEnv(sc, 1)
    safe.reset(seed=0)
    for _ in range(20):
        _, _, term, _, info = safe.step(act[:1])
        assert not term[0], info["violation"]


def test_goal_moves_are_held_and_shipped_scenarios_run_batched():
    env = BatchedEnv(scenarios.Warehouse(), 3)
    obs, _ = env.reset(seed=1)
    assert obs.shape == (3, 6, 18) and env.scenario.types[:2] == ("green", "red")
    before = env.sim.poses.copy()
    env.step(np.full((3, 6), 1))  # everyone one move (0.2 m) to +x, held for 29 ticks
    moved = env.sim.poses[..., 0] - before[..., 0]
    assert np.all(moved > 0.03) and np.all(moved < 0.2 + 1e-9)  # towards the goal 0.2 m ahead (turning first)
    pcp = BatchedEnv(scenarios.PredatorCapturePrey(), 2)
    obs, _ = pcp.reset(seed=1)
    obs, rew, *_ = pcp.step(np.full((2, 4), 4))
    assert obs.shape == (2, 4, 16) and np.allclose(rew, -0.05)  # nothing sensed from the start: the time penalty
