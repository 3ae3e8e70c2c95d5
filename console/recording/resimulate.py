"""Re-simulation: a recording's input datagrams through the real parsers into a fresh loop.

:func:`resimulate` rebuilds the recorded run on a virtual clock — a new
:class:`~swarmdeck.console.runtime.loop.ControlLoop` with simulated robots starting at
the first frame's poses, configured from the recording's ``config`` message
(``config.loop``: :func:`loop_config_to_dict`; ``config.inputs``: the
``[inputs]`` table that ``InputConfig.from_dict`` reads), socket-free
:class:`~swarmdeck.inputs.InputSource` s fed with every recorded datagram
whose receive time is at or before each tick, and the loop's clock set to each
recorded frame's time. The operator's actions are replayed before the tick they took effect in:
recordings made with ``Recorder.follow`` (``config.operator_events``) carry every action as a typed
event (``/swarmdeck/operator``, :mod:`swarmdeck.console.runtime.operator_events`: run, pause, step,
e-stop, release, behaviour switches, parameters, density bumps) and the loop gets exactly those
(:meth:`~swarmdeck.console.runtime.commands.OperatorCommands.apply`); older recordings have none, and
their actions are reconstructed from the frames (run state and run time, ``behaviour``, ``params``;
bumps painted in the browser are then lost). Each new Frame is compared with the
recorded one; with unchanged code the two are identical (except wall-clock
``timing`` and ``barrier.solve_time_s``), and the first difference says where
a change in the code (or an action that could not be replayed) altered the run. This turns a bug
report's recording into a reproducible test.
"""
from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from swarmdeck.console.recording.codec import (
    CODEC_FORMAT,
    COMPACT_FORMAT,
    RecordedDatagram,
    decode_frame,
    encode_frame,
)
from swarmdeck.console.recording.reader import Recording
from swarmdeck.console.runtime import params
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.safety.guard import GuardConfig

#: Frame keys not compared: wall-clock measurements and free-text messages.
IGNORED_KEYS = frozenset({"timing", "events", "alerts", "health"})
IGNORED_BARRIER_KEYS = frozenset({"solve_time_s"})


def loop_config_to_dict(config: Any) -> dict[str, Any]:
    """A ``LoopConfig`` as JSON-able nested dicts (inverse: :func:`loop_config_from_dict`)."""
    return params.to_dict(config)


def loop_config_from_dict(d: Mapping[str, Any]) -> Any:
    """Rebuild a ``LoopConfig`` from :func:`loop_config_to_dict` output; ValueError for bad data."""
    try:
        return params.from_dict(params.LoopConfig, d)
    except TypeError as exc:
        raise ValueError(f"recorded loop configuration is not a LoopConfig: {exc}") from None


def _with_worker_setting(loop: Mapping[str, Any]) -> dict[str, Any]:
    """A recorded loop configuration with its ``coverage_worker``: a recording made before the setting
    existed ran coverage synchronously ("off"), whatever today's default would pick for its N."""
    return {"coverage_worker": "off", **dict(loop)}


def session_metadata(loop_config: Any, inputs: Mapping[str, Any] | None = None, *,
                     robots: list[int] | None = None, source: str = "simulation",
                     guard: GuardConfig | None = GuardConfig(), **extra: Any) -> dict[str, Any]:
    """The ``metadata`` the console passes to ``Recorder``: robots, bounds and the ``config``
    that :func:`resimulate` needs (``loop``: the LoopConfig; ``inputs``: the ``[inputs]`` table
    as read from the TOML file, or None for the defaults; ``source``: "simulation" or the robot/tracker source;
    ``guard``: the loop's guard of a switched-off barrier, None when it ran without one)."""
    cfg = loop_config_to_dict(loop_config)
    return {
        "robots": list(range(loop_config.n_robots)) if robots is None else [int(r) for r in robots],
        "bounds": list(loop_config.bounds),
        "config": {"loop": cfg, "inputs": None if inputs is None else dict(inputs), "source": source,
                   "guard": None if guard is None else dataclasses.asdict(guard), **extra},
    }


def recorded_guard(config: Mapping[str, Any]) -> GuardConfig | None:
    """The guard a recorded session ran with (its ``config.guard``). Recordings from before the guard existed
    have no such key: their loop ran without one, and so does their re-simulation."""
    guard = config.get("guard")
    return None if guard is None else GuardConfig(**dict(guard))


@dataclass(frozen=True)
class Difference:
    """First divergence: tick, the key path (``"poses"``, ``"barrier.active_pairs"``), max |Δ| for numbers."""

    tick: int
    key: str
    max_abs: float | None
    recorded: str
    resimulated: str


@dataclass(frozen=True)
class ResimulationResult:
    """``frames`` compared, ``identical`` frames, datagrams fed, the first :class:`Difference` (None if
    none), per-key counts of differing frames, and notes on what could not be reproduced."""

    frames: int
    identical: int
    datagrams: int
    first_difference: Difference | None
    differing_keys: dict[str, int]
    notes: tuple[str, ...]

    @property
    def ok(self) -> bool:
        return self.frames > 0 and self.identical == self.frames

    def summary(self) -> str:
        head = (f"re-simulated {self.frames} frames with {self.datagrams} input datagrams: "
                f"{self.identical} identical")
        if self.first_difference is not None:
            d = self.first_difference
            mag = "" if d.max_abs is None else f" (max |Δ| {d.max_abs:.3g})"
            head += f"; first difference at tick {d.tick} in {d.key}{mag}"
        return "\n".join([head, *self.notes])


def _diff(a: Any, b: Any, path: str) -> tuple[str, float | None] | None:
    """First differing key path between two JSON-like values (None if equal)."""
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            if path == "" and k in IGNORED_KEYS or path == "barrier" and k in IGNORED_BARRIER_KEYS:
                continue
            r = _diff(a.get(k), b.get(k), f"{path}.{k}" if path else k)
            if r is not None:
                return r
        return None
    if a == b:
        return None
    try:
        x, y = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        if x.shape == y.shape and x.size:
            m = float(np.nanmax(np.abs(x - y))) if np.isfinite(x).all() and np.isfinite(y).all() else math.inf
            return path, m
    except (TypeError, ValueError):
        pass
    return path, None


def compare_frames(recorded: Frame, resimulated: Frame) -> list[tuple[str, float | None]]:
    """Top-level keys (and first differing path inside each) where two frames differ."""
    a, b = recorded.to_dict(), resimulated.to_dict()
    out = []
    for k in sorted(set(a) | set(b)):
        if k in IGNORED_KEYS:
            continue
        r = _diff(a.get(k), b.get(k), k)
        if r is not None:
            out.append(r)
    return out


def _replay_actions(loop: Any, events: list[Any], notes: list[str]) -> None:
    """Before the tick they took effect in: the recorded operator events, in order (one that cannot be
    replayed here is noted and skipped)."""
    for stamped in events:
        try:
            loop.apply(stamped.event)
        except ValueError as exc:
            notes.append(f"tick {stamped.tick}: operator action {type(stamped.event).__name__} not replayed: {exc}")


def _apply_operator_actions(loop: Any, prev: Frame | None, frame: Frame, nxt: Frame | None) -> None:
    """Recordings without operator events: before the tick that produced ``frame``, put the loop in the
    state the frame records."""
    p = frame.params
    # behaviour parameters and the barrier, when they differ from the loop's
    bp = loop.behaviour_params
    changes = {f: p[k] for k, f in params.frame_keys(params.BehaviourParams).items()
               if k in p and getattr(bp, f) != p[k]}
    if changes:
        loop.set_params(**changes)
    sp = loop.safety_params
    schanges = {f: p[k] for k, f in params.frame_keys(params.SafetyParams).items()
                if k in p and getattr(sp, f) != p[k]}
    if schanges:
        loop.set_safety(**schanges)
    for k, f in params.frame_keys(params.DensityParams).items():
        if k in p and getattr(loop.density.params, f) != p[k]:
            loop.set_density(**{f: p[k]})
    if frame.behaviour != loop.behaviour_name:
        loop.set_behaviour(frame.behaviour)
    # run state
    state = loop.run_state
    if frame.run_state == "estop":
        if state != "estop":
            loop.estop()
        return
    if state == "estop":
        loop.release()
    if frame.run_state == "running":
        if loop.run_state != "running":
            loop.run()
    else:  # paused: a step if behaviour time advanced over this tick
        if loop.run_state != "paused":
            loop.pause()
        if nxt is not None and nxt.run_time > frame.run_time:
            loop.step(1)


def _route(sources: list[Any], names: list[str], d: RecordedDatagram) -> Any:
    if d.listener is not None and d.listener in names:
        return sources[names.index(d.listener)]
    for s in sources:
        if s.config.transport == d.transport:
            return s
    return sources[0]


def resimulate(recording: Recording, *, max_frames: int | None = None,
               notes: list[str] | None = None) -> Iterator[tuple[Frame, Frame]]:
    """Yield ``(recorded, resimulated)`` frame pairs, tick by tick (see the module docstring); operator
    actions that could not be replayed are appended to ``notes``.

    Raises ValueError when the recording lacks what a re-simulation needs (no frames, a
    configuration that does not rebuild)."""
    from swarmdeck.console.runtime.loop import ControlLoop
    from swarmdeck.devices import ArenaConfig
    from swarmdeck.devices.simulated_robots import SimulatedRobots
    from swarmdeck.inputs import ContactDensity, InputConfig, InputHub, InputSource

    first = recording.first_frame
    if first is None:
        raise ValueError(f"{recording.path} holds no readable frame")
    cfg = recording.config().get("config", {}) or {}
    loop_cfg = loop_config_from_dict(_with_worker_setting(cfg["loop"])) if cfg.get("loop") else None
    if loop_cfg is None:
        from swarmdeck.console.runtime.loop import LoopConfig

        loop_cfg = LoopConfig(n_robots=first.n, dt=first.dt, bounds=first.bounds, behaviour=first.behaviour)
    loop_cfg = dataclasses.replace(loop_cfg, n_robots=first.n)
    inputs_cfg = InputConfig.from_dict(dict(cfg["inputs"])) if cfg.get("inputs") else InputConfig(bounds=first.bounds)
    sources = [InputSource(lc) for lc in inputs_cfg.listeners]
    names = [lc.name for lc in inputs_cfg.listeners]
    now = [first.time]
    hub = InputHub(sources, clock=lambda: now[0], config=inputs_cfg)
    robots: SimulatedRobots | None = None
    if loop_cfg.seed is not None:  # the same seeded initial conditions as the recorded run, bit for bit
        robots = SimulatedRobots(loop_cfg.n_robots, ArenaConfig(bounds=loop_cfg.bounds, dt=loop_cfg.dt,
                                                                seed=loop_cfg.seed))
        if not np.array_equal(robots.read().poses, first.poses):
            robots = None
    else:
        robots = None
    if robots is None:  # start where the recording starts (θ re-wrapped: may differ in the last bit)
        robots = SimulatedRobots(first.n, ArenaConfig(bounds=loop_cfg.bounds, dt=loop_cfg.dt),
                                 initial_poses=first.poses)
    loop = ControlLoop(loop_cfg, source=robots, sink=robots, inputs=hub, guard=recorded_guard(cfg),
                       contact_density=ContactDensity(inputs_cfg.density), clock=lambda: now[0])
    compact = recording.metadata.get("frame_format") in (COMPACT_FORMAT, CODEC_FORMAT)
    notes = notes if notes is not None else []
    actions: dict[int, list[Any]] | None = None
    if cfg.get("operator_events"):
        actions = {}
        for stamped in recording.operator_events():
            actions.setdefault(stamped.tick, []).append(stamped)
    datagrams = iter(recording.datagrams())
    pending = next(datagrams, None)
    frames = recording.frames()
    cur = next(frames, None)
    prev: Frame | None = None
    count = 0
    try:
        while cur is not None and (max_frames is None or count < max_frames):
            nxt = next(frames, None)
            frame = cur[1]
            now[0] = frame.time
            while pending is not None and pending.t <= frame.time:
                _route(sources, names, pending).feed(pending.data, pending.peer, pending.t, pending.transport)
                pending = next(datagrams, None)
            if actions is None:
                _apply_operator_actions(loop, prev, frame, None if nxt is None else nxt[1])
            else:
                _replay_actions(loop, actions.pop(frame.tick, []), notes)
            sim = loop.tick()
            # compare at the recording's precision: the new frame as it would have been recorded
            yield frame, (decode_frame(encode_frame(sim)) if compact else sim)
            prev, cur = frame, nxt
            count += 1
    finally:
        loop.close()


def resimulate_and_compare(recording: Recording, *, max_frames: int | None = None) -> ResimulationResult:
    """Run :func:`resimulate` to the end and summarise the comparison."""
    frames = identical = 0
    first: Difference | None = None
    keys: dict[str, int] = {}
    notes: list[str] = []
    for rec, sim in resimulate(recording, max_frames=max_frames, notes=notes):
        frames += 1
        diffs = compare_frames(rec, sim)
        if not diffs:
            identical += 1
            continue
        for path, _ in diffs:
            top = path.split(".")[0]
            keys[top] = keys.get(top, 0) + 1
        if first is None:
            path, mag = diffs[0]
            top = path.split(".")[0]
            first = Difference(rec.tick, path, mag, str(rec.to_dict().get(top))[:200], str(sim.to_dict().get(top))[:200])
    dgs = list(recording.datagrams())
    n_dg = len(dgs)
    cfg = recording.config().get("config", {}) or {}
    listeners = (cfg.get("inputs") or {}).get("listeners") or []
    transports = [str(lc.get("transport", "udp")) for lc in listeners if isinstance(lc, dict)]
    if any(d.listener is None for d in dgs) and len(transports) != len(set(transports)):
        notes.append("datagrams were recorded without their listener's name and several listeners share a "
                     "transport: they were all replayed into the first one (record with Recorder.datagram_hook)")
    if not cfg.get("loop"):
        notes.append("the recording has no loop configuration (config.loop): defaults were used")
    if cfg.get("source", "simulation") != "simulation":
        notes.append(f"recorded with robots from {cfg.get('source')!r}: re-simulated robots follow the model, "
                     "not the real floor, so poses diverge")
    if "density" in keys and not cfg.get("operator_events"):
        notes.append("the density differs: density bumps added or moved in the browser are not replayed")
    return ResimulationResult(frames, identical, n_dg, first, keys, tuple(notes))
