"""swarmdeck.envs: learning environments on the simulated arena (``pip install 'swarmdeck[rl]'``).

    import swarmdeck.envs
    env = swarmdeck.envs.parallel_env(n_robots=10, task="coverage")   # PettingZoo ParallelEnv
    obs, infos = env.reset(seed=0)
    while env.agents:
        actions = {a: env.action_space(a).sample() for a in env.agents}
        obs, rewards, terminations, truncations, infos = env.step(actions)
        # infos[a]["filter_change"]: how much the safety filter changed robot a's command, m/s

    single = swarmdeck.envs.CentralisedEnv(n_robots=10, task="rendezvous")  # Gymnasium Env

    batched = swarmdeck.envs.BatchedEnv(swarmdeck.envs.scenarios.Rendezvous(n_agents=10), n_envs=64)
    obs, info = batched.reset(seed=0)          # (64, 10, D): 64 swarms stepped at once (swarmdeck.envs.batched)

Every action passes the barrier-certificate safety filter of ``swarmdeck.safety``
(through ``swarmdeck.devices.Arena``) unless ``safety=False``. Episodes can be
recorded to MCAP and played in the console: ``swarmdeck.console.recording.episodes``.
"""
from swarmdeck.envs import scenarios
from swarmdeck.envs.batched import BatchedEnv, ScenarioParallelEnv, SwarmVectorEnv
from swarmdeck.envs.centralised import CentralisedEnv
from swarmdeck.envs.scenario import Actions, Scenario, View
from swarmdeck.envs.swarm import ACTIONS, EnvConfig, SwarmParallelEnv, parallel_env
from swarmdeck.envs.tasks import TASKS

__all__ = ["ACTIONS", "Actions", "BatchedEnv", "CentralisedEnv", "EnvConfig", "Scenario", "ScenarioParallelEnv",
           "SwarmParallelEnv", "SwarmVectorEnv", "TASKS", "View", "parallel_env", "scenarios"]
