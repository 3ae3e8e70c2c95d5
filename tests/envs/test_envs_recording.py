"""Learning episodes are recorded as swarmdeck sessions: one file per episode, played by the console's player and scene."""
from __future__ import annotations

import numpy as np
import pytest
import viser

import swarmdeck.envs as envs
from swarmdeck.console.recording.episodes import record_episodes
from swarmdeck.console.recording.foxglove import TOPIC_ROBOTS
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.web.player import Player
from swarmdeck.console.web.scene import ArenaScene


@pytest.fixture(scope="module")
def episodes(tmp_path_factory):
    folder = tmp_path_factory.mktemp("episodes")
    env = record_episodes(envs.parallel_env(n_robots=5, task="coverage", max_steps=12), folder)
    poses = []
    for seed in (0, 1):
        env.reset(seed=seed)
        ep = []
        while env.agents:
            ep.append(env.unwrapped.arena.poses())
            env.step({a: env.action_space(a).sample() for a in env.agents})
        poses.append(ep)
    env.close()
    return env.paths, poses


def test_each_episode_is_a_recording_of_its_steps(episodes):
    paths, poses = episodes
    assert [p.name for p in paths] == ["episode-000.mcap", "episode-001.mcap"]
    for path, ep in zip(paths, poses):
        with open_recording(path) as r:
            assert r.indexed  # closed cleanly at the end of the episode
            frames = [f for _, f in r.frames()]
            assert [f.tick for f in frames] == list(range(12))
            assert all(np.array_equal(f.poses, p) for f, p in zip(frames, ep))
            f = frames[-1]
            assert f.coverage is not None and f.density is not None and f.behaviour == "env:coverage"
            assert f.barrier.enabled and f.params["reward_sum"] < 0
            assert r.config()["config"]["env"]["n_robots"] == 5
            assert r.message_counts()[TOPIC_ROBOTS] == 12  # the Foxglove channels too


def test_an_episode_plays_in_the_console_scene(episodes):
    paths, _ = episodes
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        scene = ArenaScene(server)
        with open_recording(paths[1]) as r:
            player = Player(r, clock=lambda: 0.0)
            seen = []
            for _ in range(12):
                scene.draw(player.frame)
                seen.append(player.frame.tick)
                player.step()
        assert seen[:3] == [0, 1, 2] and seen[-1] == 11
    finally:
        server.stop()
