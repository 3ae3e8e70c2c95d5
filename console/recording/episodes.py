"""Recording learning episodes (``swarmdeck.envs``) as swarmdeck sessions: ``swarmdeck play`` and Foxglove open them.

    from swarmdeck.envs import parallel_env
    from swarmdeck.console.recording.episodes import record_episodes

    env = record_episodes(parallel_env(n_robots=10, task="coverage"), "episodes/")
    obs, infos = env.reset(seed=0)            # starts episodes/episode-000.mcap
    while env.agents:
        obs, rewards, terms, truncs, infos = env.step({a: env.action_space(a).sample() for a in env.agents})
    env.close()                               # finishes the file; `swarmdeck play episodes/episode-000.mcap`

Each step becomes one :class:`~swarmdeck.console.runtime.frame.Frame` (the
poses the actions were applied at, the agents' commands as nominal, the
filtered ones as safe, the barrier's diagnostics, the coverage cells and the
density for the coverage task, the rewards in ``params``), written by the
console's :class:`~swarmdeck.console.recording.recorder.Recorder` — so the
file has the same channels as a console session, Foxglove's included. Each
``reset`` starts a new file ``episode-NNN.mcap`` in the folder.
"""
from __future__ import annotations

import dataclasses
import os
from pathlib import Path
from typing import Any

import numpy as np

from swarmdeck.console.recording.recorder import Recorder
from swarmdeck.console.runtime.frame import CoverageFrame, Frame

try:
    from pettingzoo.utils import BaseParallelWrapper
except ImportError as _exc:  # pragma: no cover - exercised only without the extra
    raise ImportError("recording episodes needs the 'rl' extra: pip install 'swarmdeck[rl]'") from _exc


class EpisodeRecorder(BaseParallelWrapper):
    """A PettingZoo wrapper that records every episode of a ``SwarmParallelEnv`` to ``folder/episode-NNN.mcap``."""

    def __init__(self, env: Any, folder: str | os.PathLike[str]) -> None:
        super().__init__(env)
        self.folder = Path(folder)
        self.episode = -1
        self.recorder: Recorder | None = None
        self.paths: list[Path] = []
        self._seed: int | None = None

    @property
    def swarm(self) -> Any:
        return self.env.unwrapped

    def _finish(self) -> None:
        if self.recorder is not None:
            self.recorder.close()
            self.recorder = None

    def reset(self, seed: int | None = None, options: dict | None = None) -> tuple[dict, dict]:
        self._finish()
        out = self.env.reset(seed=seed, options=options)
        self.episode += 1
        env = self.swarm
        cfg = env.config
        path = self.folder / f"episode-{self.episode:03d}.mcap"
        meta = {"robots": list(range(cfg.n_robots)), "bounds": list(cfg.bounds),
                "config": {"source": "swarmdeck.envs", "env": dataclasses.asdict(cfg), "seed": seed,
                           "episode": self.episode}}
        self.recorder = Recorder(path, meta)
        self.paths.append(path)
        return out

    def step(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        env = self.swarm
        poses = env.arena.poses() if env.arena is not None else None
        tick = env.steps
        out = self.env.step(actions)
        if self.recorder is not None and poses is not None:
            self.recorder.write_frame(episode_frame(env, poses, tick, out[1]))
        if not self.env.agents:
            self._finish()
        return out

    def close(self) -> None:
        self._finish()
        self.env.close()


def record_episodes(env: Any, folder: str | os.PathLike[str]) -> EpisodeRecorder:
    """Wrap ``env`` (a ``swarmdeck.envs`` parallel env) so that each episode is recorded to ``folder``."""
    return EpisodeRecorder(env, folder)


def episode_frame(env: Any, poses: np.ndarray, tick: int, rewards: dict[str, float]) -> Frame:
    """The Frame of the step just taken by ``env`` from ``poses`` (N, 3) at step index ``tick``."""
    from swarmdeck.console.recording.arena_recording import arena_frame
    from swarmdeck.core.kinematics import lookahead_points

    arena = env.arena
    cfg = env.config
    coverage = None
    if env.density is not None:
        from swarmdeck.coverage import CoverageConfig, coverage_tick

        _, state, _ = coverage_tick(lookahead_points(poses, arena.ell), env.density, CoverageConfig(bounds=cfg.bounds))
        coverage = CoverageFrame.from_state(state) if state.ok else None
    r = np.array([rewards.get(a, 0.0) for a in env.possible_agents])
    frame = arena_frame(arena, poses, tick, f"env:{cfg.task}",
                        params={"task": cfg.task, "action": cfg.action, "safety": cfg.safety,
                                "reward_sum": float(r.sum()), "reward_min": float(r.min()),
                                "reward_max": float(r.max())},
                        coverage=coverage, density=env.density)
    return frame
