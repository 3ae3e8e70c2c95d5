"""Record the Arenas of a headless run (``swarmdeck run --record PATH``) as the console records a session.

One :class:`~swarmdeck.console.recording.recorder.Recorder` per Arena the script builds, with the console's
:func:`~swarmdeck.console.recording.resimulate.session_metadata` (a ``LoopConfig`` describing the run,
behaviour ``script:NAME``), one Frame per step (:func:`arena_frame`): ``swarmdeck play``, ``swarmdeck info``
and Foxglove open it like any session. The first Arena goes to ``PATH``, the k-th to ``PATH-k.mcap``.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.runtime.frame import BarrierFrame, Frame
from swarmdeck.console.runtime.network_frame import NetworkFrame
from swarmdeck.console.runtime.sensors_frame import SensorsFrame
from swarmdeck.core.bounds import Bounds
from swarmdeck.core.constants import SAFETY_DISTANCE
from swarmdeck.core.kinematics import si_to_unicycle


def arena_frame(arena: Any, poses: NDArray[np.float64], tick: int, behaviour: str,
                params: dict[str, Any] | None = None, **extra: Any) -> Frame:
    """The Frame of the step ``arena`` just took from ``poses`` (N, 3), step index ``tick``: its nominal and
    safe look-ahead velocities (m/s), the unicycle commands they give and the barrier's diagnostics."""
    n = arena.n
    dt = arena.config.dt
    safe = np.asarray(arena.last_safe, dtype=float)
    v, w = si_to_unicycle(poses, safe, arena.ell)
    diag = arena.safety_stats.last_diagnostics if arena.safety is not None else None
    d_s = float(getattr(getattr(arena.safety, "config", None), "safety_distance", SAFETY_DISTANCE))
    barrier = (BarrierFrame.from_diagnostics(diag, n, d_s)
               if diag is not None else BarrierFrame(enabled=False, intervention=np.zeros(n)))
    network = getattr(arena, "network", None)  # a decentralised run's messages (devices/decentralised.py)
    if network is not None and "network" not in extra:
        traffic = network.traffic()
        extra["network"] = NetworkFrame.from_traffic(traffic.links, traffic.messages, dt)
    drawn = getattr(arena, "last_annotations", None)
    if drawn is not None and len(drawn) and "annotations" not in extra:
        extra = {**extra, "annotations": drawn}  # what the script drew this step (Arena.draw)
    return Frame(tick=tick, time=tick * dt, run_time=tick * dt, dt=dt, bounds=arena.config.bounds,
                 lookahead=arena.ell, poses=poses, ids=np.arange(n), nominal=arena.last_nominal, safe=safe, v=v, w=w,
                 barrier=barrier, behaviour=behaviour, params=dict(params or {}),
                 **{"obstacles": getattr(arena.config, "obstacles", None), **extra})


def sensors_frame(arena: Any) -> SensorsFrame | None:
    """What ``arena``'s robots sensed at their current poses (None: the Arena has no sensors)."""
    sensors = getattr(arena, "sensors", None)
    if sensors is None:
        return None
    return SensorsFrame.of(arena.sense(), sensors.config)


class ArenaRecording:
    """``on_create``/``on_step`` hooks for :func:`~swarmdeck.devices.runner.run_experiment` that record.

    ``path``: the MCAP file of the first Arena; ``script``: the script's path (names the behaviour);
    ``seed``: the run's seed (in the metadata); ``foxglove_channels``: also write Foxglove's own channels
    (``swarmdeck run --record PATH --no-foxglove-channels``: only swarmdeck's); ``foxglove_entities``: the robots as
    an entity each (``--foxglove-entities``; default one packed PointCloud, ``FoxgloveConfig``); ``capsule``/``capsule_files``: what
    reproduces the run (a ``capsule.Manifest`` and the script files, relative path → bytes), written into every
    recording with ``run.arena`` set to the Arena's index (``swarmdeck capsule PATH -o run.zip``).
    """

    def __init__(self, path: str | Path, *, script: str | Path, seed: int | None = None,
                 foxglove_channels: bool = True, capsule: Any = None,
                 capsule_files: dict[str, bytes] | None = None, foxglove_entities: bool = False) -> None:
        self.path = Path(path)
        self.foxglove_entities = bool(foxglove_entities)
        self.capsule = capsule
        self.capsule_files = dict(capsule_files or {})
        self.foxglove_channels = bool(foxglove_channels)
        self.behaviour = f"script:{Path(script).name}"
        self.seed = seed
        self._recorders: dict[int, Any] = {}
        self._previous: dict[int, NDArray[np.float64]] = {}
        self._ticks: dict[int, int] = {}
        self._sensed: dict[int, SensorsFrame | None] = {}  # what the robots sensed at the poses of _previous
        self.paths: list[Path] = []

    def _path(self, k: int) -> Path:
        return self.path if k == 0 else self.path.with_name(f"{self.path.stem}-{k + 1}{self.path.suffix or '.mcap'}")

    def on_create(self, arena: Any) -> None:
        """Open the recording of a new Arena (its start poses are the first frame's); it reads the Arena's
        annotations (:meth:`~swarmdeck.devices.arena.Arena.read_annotations`)."""
        read = getattr(arena, "read_annotations", None)
        if read is not None:
            read()
        from swarmdeck.console.recording.foxglove import FoxgloveConfig
        from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
        from swarmdeck.console.recording.resimulate import session_metadata
        from swarmdeck.console.runtime.loop import LoopConfig, SafetyParams

        config = LoopConfig(n_robots=arena.n, dt=arena.config.dt, bounds=Bounds.of(arena.config.bounds), seed=self.seed,
                            behaviour=self.behaviour, safety=SafetyParams(enabled=arena.safety is not None),
                            obstacles=getattr(arena.config, "obstacles", None))
        k = len(self._recorders)
        path = self._path(k)
        self.paths.append(path)
        capsule = None
        if self.capsule is not None:
            from dataclasses import replace

            capsule = replace(self.capsule, run={**self.capsule.run, "arena": k}).to_dict()
        self._recorders[id(arena)] = Recorder(path, session_metadata(config, None, source="simulation",
                                                                      run="swarmdeck run"),
                                              RecorderConfig(foxglove=self.foxglove_channels), capsule=capsule,
                                              foxglove=FoxgloveConfig.per_entity() if self.foxglove_entities else None,
                                              capsule_files=self.capsule_files if capsule is not None else None)
        self._previous[id(arena)] = arena.poses()
        self._ticks[id(arena)] = 0
        self._sensed[id(arena)] = sensors_frame(arena)

    def on_step(self, arena: Any) -> None:
        """Write the step ``arena`` just took."""
        rec = self._recorders.get(id(arena))
        if rec is None:
            return
        tick = self._ticks[id(arena)]
        sensed = self._sensed.get(id(arena))
        rec.write_frame(arena_frame(arena, self._previous[id(arena)], tick, self.behaviour, sensors=sensed))
        self._previous[id(arena)] = arena.poses()
        self._sensed[id(arena)] = sensors_frame(arena)
        self._ticks[id(arena)] = tick + 1

    def close(self) -> list[str]:
        """Finish every file; one line per recording (where it is, or why it failed)."""
        lines = []
        for rec in self._recorders.values():
            status = rec.close()
            lines.append(f"recorded {status.frames} frames to {status.path}" if status.ok else status.message)
        return lines
