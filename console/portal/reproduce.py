"""Re-execute a portal job from its capsule: its script in the sandbox, on a simulated loop like the arena's.

The arena runner (:mod:`.runner`) runs a job's script in the jail against a
:class:`~swarmdeck.console.runtime.loop.ControlLoop` whose behaviour is :class:`.runner.SandboxCommands`; it records
the loop's Frames (without the density layer) after the robots' set-up, the first one paused at the start poses.
:func:`resimulate_job` builds the same loop from the recording's ``config`` (loop configuration, guard, bypass), with
simulated robots starting at the first recorded frame's poses and a virtual clock, runs the capsule's script in the
sandbox against it (the limits of a fast arena), and pairs its Frames with the recorded ones for
:func:`~swarmdeck.console.recording.capsule_run.compare_pairs`.

Not reproduced, and named in the notes: a job on physical robots (``source`` not "simulation") and the fleet's
batteries (the reproduction's robots start fully charged, the fleet's did not: ``battery`` and ``charging`` are left
out of the comparison, :data:`FLEET_ONLY_KEYS`).
"""
from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.recording.codec import CODEC_FORMAT, COMPACT_FORMAT, decode_frame, encode_frame
from swarmdeck.console.runtime.frame import Frame

#: Frame keys of the fleet's hardware a simulated reproduction does not model (not compared).
FLEET_ONLY_KEYS = ("battery", "charging")


def _without_fleet(frame: Frame) -> Frame:
    """``frame`` with the fleet-only keys at their defaults (battery unknown, not charging)."""
    return dataclasses.replace(frame, battery=None, charging=None)


def resimulate_job(recording: Any, opened: Any, *, notes: list[str],
                   counts: dict[str, int] | None = None) -> Iterator[tuple[Frame, Frame]]:
    """``(recorded, reproduced)`` Frame pairs of a portal job's capsule ``opened``
    (:class:`~swarmdeck.console.recording.capsule_zip.OpenedCapsule`) re-executed against ``recording`` (its open
    :class:`~swarmdeck.console.recording.reader.Recording`); what could not be reproduced goes to ``notes``, the
    number of Frames the reproduction made to ``counts["reproduced"]``.
    ValueError when the recording lacks what the loop needs."""
    from swarmdeck.console.portal.runner import SandboxCommands
    from swarmdeck.console.recording.resimulate import loop_config_from_dict, recorded_guard
    from swarmdeck.console.runtime.loop import ControlLoop
    from swarmdeck.console.sandbox.confinement import ConfinementUnavailable, JailConfig, SandboxLimits
    from swarmdeck.console.sandbox.plant import SandboxPlant
    from swarmdeck.console.sandbox.run import run_sandboxed
    from swarmdeck.core.bounds import DEFAULT_BOUNDS
    from swarmdeck.devices import ArenaConfig
    from swarmdeck.devices.simulated_robots import SimulatedRobots

    first = recording.first_frame
    if first is None:
        raise ValueError(f"{recording.path} holds no readable frame")
    cfg = recording.config().get("config", {}) or {}
    if not cfg.get("loop"):
        raise ValueError("the recording has no loop configuration (config.loop)")
    loop_cfg = dataclasses.replace(loop_config_from_dict(cfg["loop"]), n_robots=first.n)
    run = opened.manifest.run
    script = opened.folder / opened.manifest.entry if opened.manifest.kind == "portal" and run.get("single") \
        else opened.folder
    entry = None if run.get("single") else opened.manifest.entry
    frames: list[Frame] = []

    def make_plant(n_script: int, script_initial: NDArray[np.float64] | None) -> SandboxPlant:
        robots = SimulatedRobots(first.n, ArenaConfig(bounds=loop_cfg.bounds, dt=loop_cfg.dt,
                                                      obstacles=loop_cfg.obstacles), initial_poses=first.poses)
        loop = ControlLoop(loop_cfg, source=robots, sink=robots, guard=recorded_guard(cfg))
        state["loop"] = loop
        loop.subscribe(lambda f: frames.append(f if f.density is None else dataclasses.replace(f, density=None)))
        commands = SandboxCommands(loop_cfg.bounds, on_warning=loop.post)
        loop.use_behaviour(commands)
        if cfg.get("bypass"):
            loop.set_safety(enabled=False)
        loop.pause()
        loop.tick()
        loop.run()
        return SandboxPlant.on_loop(loop, commands, float(run["duration"]), None)

    state: dict[str, Any] = {"loop": None}
    try:
        region = None if loop_cfg.bounds == DEFAULT_BOUNDS else loop_cfg.bounds  # a region of a shared floor
        outcome = run_sandboxed(script, make_plant, entry=entry, n_robots=int(run["robots"]),
                                duration=float(run["duration"]), limits=SandboxLimits(), jail=JailConfig(),
                                bounds=region)
    except ConfinementUnavailable as exc:
        raise ValueError(f"the job's script cannot be sandboxed here: {exc}") from None
    finally:
        loop = state["loop"]
        if loop is not None:
            if loop.run_state == "estop" and (loop.latest is None or loop.latest.run_state != "estop"):
                loop.tick()  # as the runner records an emergency stop the run ended on
            loop.close()
    if outcome.error_line:
        notes.append(f"the reproduced script ended: {outcome.error_line}")
    if cfg.get("source", "simulation") != "simulation":
        notes.append(f"the job ran on robots from {cfg.get('source')!r}; the reproduction simulates them")
    notes.append("the fleet's batteries (battery, charging) are not compared: the reproduction's robots start charged")
    if counts is not None:
        counts["reproduced"] = len(frames)
    compact = recording.metadata.get("frame_format") in (COMPACT_FORMAT, CODEC_FORMAT)
    recorded = (f for _, f in recording.frames())
    for rec, new in zip(recorded, frames):
        # compared at the recording's precision: the new frame as it would have been recorded (as resimulate does)
        yield _without_fleet(rec), _without_fleet(decode_frame(encode_frame(new)) if compact else new)


__all__ = ["FLEET_ONLY_KEYS", "resimulate_job"]
