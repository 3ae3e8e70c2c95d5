"""One command trains a small policy on a shipped scenario and submits it to the portal (issue 27 item 3):
`swarmdeck train SCENARIO --submit` trains PPO (Stable-Baselines3) on the batched environment, writes the policy
as plain numpy weights beside an experiment script, and the portal's sandboxed verification runs that script with
the policy inside the barrier; a corrupted policy file is rejected there with the loader's message."""
from __future__ import annotations

import json
import zipfile

import httpx
import numpy as np
import pytest
from portal_fixtures import wait_for_state

from swarmdeck.console.cli import main as cli
from swarmdeck.console.portal.workers import VerificationWorkers
from swarmdeck.console.sandbox.executors import SerialExecutor
from swarmdeck.envs.batched import BatchedEnv
from swarmdeck.envs.scenarios import make_scenario
from swarmdeck.envs.train import SwarmSB3VecEnv, export_actor, ppo


def test_the_vec_env_restarts_an_ended_swarm_at_once_and_keeps_its_last_observation():
    venv = SwarmSB3VecEnv(BatchedEnv(make_scenario("rendezvous", n_agents=2, max_steps=2), 2, safety=False))
    venv.seed(3)
    first = venv.reset()
    assert first.shape == (4, venv.observation_space.shape[0])
    zero = np.zeros((4, 2), dtype=np.float32)
    venv.step_async(zero)
    _, _, dones, infos = venv.step_wait()
    assert not dones.any() and infos == [{}] * 4
    venv.step_async(zero)
    obs, rewards, dones, infos = venv.step_wait()
    assert dones.all() and rewards.shape == (4,)
    assert all("terminal_observation" in i and i["TimeLimit.truncated"] for i in infos)
    np.testing.assert_array_equal(venv.env.steps, [0, 0])  # restarted in this very step, SB3's convention
    assert not np.array_equal(obs, np.stack([i["terminal_observation"] for i in infos]))


@pytest.mark.parametrize("scenario", ["rendezvous", "predator_capture_prey"])
def test_the_exported_numpy_actor_gives_sb3s_deterministic_action(scenario):
    model = ppo(scenario, n_agents=3 if scenario == "rendezvous" else None, n_envs=1, steps=64, seed=1)
    policy = export_actor(model, scenario, {"n_agents": model.get_env().env.n_agents}, trained={})
    low, high = model.observation_space.low, model.observation_space.high
    obs = np.random.default_rng(2).uniform(np.maximum(low, -3), np.minimum(high, 3), size=(16, len(low)))
    obs = obs.astype(np.float32)
    expected, _ = model.predict(obs, deterministic=True)
    got = policy.act(obs)
    if scenario == "rendezvous":
        np.testing.assert_allclose(got, expected, atol=1e-5)
    else:
        np.testing.assert_array_equal(got, expected)


@pytest.fixture
def workers(portal):
    w = VerificationWorkers(portal.service, SerialExecutor(), poll_s=0.2).start()
    yield w
    w.stop()


def test_one_command_trains_and_submits_a_policy_that_verification_runs_in_the_sandbox(portal, workers, tmp_path,
                                                                                         capsys):
    out = tmp_path / "exp"
    code = cli(["train", "rendezvous", "--steps", "96", "--envs", "1", "--robots", "2", "--duration", "1",
                "--out", str(out), "--submit", "--json", "--server", portal.url, "--token", portal.tokens["alice"]])
    assert code == 0
    job = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert (out / "policy.npz").is_file() and (out / "main.py").is_file()
    with zipfile.ZipFile(tmp_path / "exp.zip") as z:
        assert sorted(z.namelist()) == ["main.py", "manifest.json", "policy.npz"]
        assert json.loads(z.read("manifest.json"))["robots"] == 2

    # the same folder runs here, in simulation, inside the barrier
    assert cli(["run", str(out / "main.py"), "--duration", "0.3", "--json"]) == 0
    printed = capsys.readouterr().out  # the script's own lines (its results), then the JSON report
    assert "mean reward per agent and step" in printed
    report = json.loads(printed[printed.index("{\n"):])["reports"][0]
    assert report["safety"]["enabled"] and report["safety"]["calls"] > 0 and report["safety"]["failures"] == 0

    # a corrupted policy file in the same archive: the loader's message reaches the verdict
    bad = tmp_path / "bad.zip"
    with zipfile.ZipFile(tmp_path / "exp.zip") as z, zipfile.ZipFile(bad, "w") as w:
        for name in z.namelist():
            w.writestr(name, z.read(name) if name != "policy.npz" else b"PK\x03\x04 truncated")
    assert cli(["submit", str(bad), "--json", "--server", portal.url, "--token", portal.tokens["alice"]]) == 0
    bad_job = json.loads(capsys.readouterr().out)

    with httpx.Client(base_url=portal.url, headers={"Authorization": f"Bearer {portal.tokens['alice']}"},
                      timeout=30) as c:
        good = wait_for_state(c, job["id"], ("in arena queue", "awaiting approval", "running", "done", "rejected"),
                              timeout=120)
        assert good["state"] != "rejected" and good["verdict"].startswith("accepted"), good
        refused = wait_for_state(c, bad_job["id"], ("rejected",), timeout=120)
        assert "PolicyError" in refused["reason"] and "policy.npz" in refused["reason"], refused
