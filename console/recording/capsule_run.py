"""Re-execute a capsule in simulation and say whether the result is bit-identical to its recording.

``swarmdeck run run.zip`` (:func:`reproduce`):

* a ``swarmdeck run`` capsule (kind ``run``) re-runs the script file with the recorded arguments through
  :func:`~swarmdeck.devices.runner.run_experiment` (as ``swarmdeck run`` does; with ``sandbox``, in the jail against
  a trusted Arena, as ``swarmdeck run --sandbox`` does) and records it with
  :class:`~swarmdeck.console.recording.arena_recording.ArenaRecording`; the two recordings are compared frame by
  frame;
* a console session (kind ``console``) is re-simulated by
  :func:`~swarmdeck.console.recording.resimulate.resimulate` (the recorded configuration, operator events and input
  datagrams on a virtual clock);
* one run of a sweep (kind ``verification``, ``swarmdeck sweep --capsules``) runs its task again in the sandbox with
  the same recording hooks (:func:`swarmdeck.console.sweep.capsules.reproduce_task`); the recordings are compared;
* a portal job (kind ``portal``) runs its script again in the sandbox on a simulated loop built as the portal built it
  (:func:`swarmdeck.console.portal.reproduce.resimulate_job`).

Frames are compared by :func:`~swarmdeck.console.recording.resimulate.compare_frames` (wall-clock ``timing`` and
solve times aside). The first difference is named by tick, time (s), robot id and quantity (a Frame key path).
The environment the capsule was recorded in is compared with this one
(:func:`~swarmdeck.console.recording.capsule.environment_differences`): a different swarmdeck, Python, machine or
package version is named, and then identical frames are reported as identical, never as a bit-identity claim.
"""
from __future__ import annotations

import sys
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from swarmdeck.console.recording.capsule import environment, environment_differences
from swarmdeck.console.recording.capsule_zip import CapsuleError, OpenedCapsule
from swarmdeck.console.recording.resimulate import compare_frames
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.devices.experiment_params import params_in_environment

#: Exit codes of ``swarmdeck run run.zip``: bit-identical; frames differ; identical frames in another environment.
EXIT_IDENTICAL, EXIT_DIFFERENT, EXIT_ENVIRONMENT = 0, 1, 3
#: Environment keys whose difference rules out a bit-identity claim (the platform string alone is only named).
BLOCKING_PREFIXES = ("swarmdeck", "python", "implementation", "machine", "package")


@dataclass(frozen=True)
class FirstDifference:
    """Where a reproduction first left its recording: ``tick``, ``time`` (s), ``robot`` (its id; None for a quantity
    of no single robot), ``quantity`` (a Frame key path, e.g. ``poses``, ``barrier.h``), the largest |Δ| of that
    quantity in that frame (None for non-numbers) and both values (truncated text)."""

    tick: int
    time: float
    robot: int | None
    quantity: str
    max_abs: float | None
    recorded: str
    reproduced: str

    def describe(self) -> str:
        who = "" if self.robot is None else f", robot {self.robot}"
        mag = "" if self.max_abs is None else f" (max |Δ| {self.max_abs:.3g})"
        return (f"first difference at t = {self.time:.3f} s (tick {self.tick}){who}, in {self.quantity}{mag}: "
                f"recorded {self.recorded}, reproduced {self.reproduced}")


@dataclass(frozen=True)
class Verdict:
    """The comparison of a reproduction with its recording: frames ``compared`` (``recorded_frames`` and
    ``reproduced_frames`` each had), the first difference, environment differences and notes."""

    compared: int
    recorded_frames: int
    reproduced_frames: int
    first: FirstDifference | None
    environment: tuple[str, ...]
    notes: tuple[str, ...] = ()

    @property
    def frames_identical(self) -> bool:
        return (self.first is None and self.compared > 0 and self.recorded_frames == self.reproduced_frames)

    @property
    def blocking_environment(self) -> tuple[str, ...]:
        """The environment differences that rule out a bit-identity claim."""
        return tuple(d for d in self.environment if d.startswith(BLOCKING_PREFIXES))

    @property
    def bit_identical(self) -> bool:
        """Every frame identical, as many frames, and the same swarmdeck, Python, machine and packages."""
        return self.frames_identical and not self.blocking_environment

    @property
    def exit_code(self) -> int:
        if not self.frames_identical:
            return EXIT_DIFFERENT
        return EXIT_IDENTICAL if self.bit_identical else EXIT_ENVIRONMENT

    def summary(self) -> str:
        lines = []
        if self.bit_identical:
            lines.append(f"bit-identical: all {self.compared} frames reproduce the recording exactly")
        elif self.frames_identical:
            lines.append(f"all {self.compared} frames are identical, but the environment differs, so bit-identity "
                         "is not claimed:")
        else:
            lines.append(f"NOT identical: {self.compared} frames compared "
                         f"(recorded {self.recorded_frames}, reproduced {self.reproduced_frames})")
            if self.first is not None:
                lines.append(self.first.describe())
            elif self.recorded_frames != self.reproduced_frames:
                lines.append(f"the reproduction has {self.reproduced_frames} frames, the recording "
                             f"{self.recorded_frames}: the runs end at different ticks")
        lines += [f"  environment: {d}" for d in self.environment]
        lines += [f"  note: {n}" for n in self.notes]
        return "\n".join(lines)

    def to_dict(self) -> dict[str, Any]:
        first = None if self.first is None else {
            "tick": self.first.tick, "time": self.first.time, "robot": self.first.robot,
            "quantity": self.first.quantity, "max_abs": self.first.max_abs}
        return {"bit_identical": self.bit_identical, "frames_identical": self.frames_identical,
                "compared": self.compared, "recorded_frames": self.recorded_frames,
                "reproduced_frames": self.reproduced_frames, "first_difference": first,
                "environment": list(self.environment), "notes": list(self.notes)}


def _at(d: Any, path: str) -> Any:
    for part in path.split("."):
        if not isinstance(d, dict):
            return None
        d = d.get(part)
    return d


def _robot(recorded: Frame, reproduced: Frame, path: str) -> int | None:
    """The id of the first robot whose row of the per-robot quantity ``path`` differs (None: not per robot)."""
    a, b = _at(recorded.to_dict(), path), _at(reproduced.to_dict(), path)
    try:
        x, y = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    except (TypeError, ValueError):
        return None
    n = recorded.n
    if x.shape != y.shape or x.ndim == 0 or x.shape[0] != n:
        return None
    rows = ~np.all((x == y) | (np.isnan(x) & np.isnan(y)), axis=tuple(range(1, x.ndim)))
    idx = np.flatnonzero(rows)
    return int(recorded.ids[idx[0]]) if idx.size else None


def _short(v: Any) -> str:
    text = str(v)
    return text if len(text) <= 120 else text[:117] + "..."


def compare_pairs(pairs: Iterable[tuple[Frame, Frame]]) -> tuple[int, FirstDifference | None]:
    """Compare ``(recorded, reproduced)`` frame pairs in order: how many, and the first difference (None: none)."""
    count = 0
    for rec, new in pairs:
        count += 1
        diffs = compare_frames(rec, new)
        if diffs:
            path, mag = diffs[0]
            return count, FirstDifference(rec.tick, float(rec.time), _robot(rec, new, path), path, mag,
                                          _short(_at(rec.to_dict(), path)), _short(_at(new.to_dict(), path)))
    return count, None


def _frames(path: Path) -> Iterator[Frame]:
    from swarmdeck.console.recording.reader import open_recording

    with open_recording(path) as rec:
        for _, frame in rec.frames():
            yield frame


def compare_recordings(recorded: Path, reproduced: Path) -> tuple[int, int, int, FirstDifference | None]:
    """Frame by frame: (compared, frames in ``recorded``, frames in ``reproduced``, first difference)."""
    from swarmdeck.console.recording.reader import open_recording

    with open_recording(recorded) as a, open_recording(reproduced) as b:
        n_a, n_b = a.count_frames(), b.count_frames()
    compared, first = compare_pairs(zip(_frames(recorded), _frames(reproduced)))
    return compared, n_a, n_b, first


def _rerun_script(opened: OpenedCapsule, workdir: Path, sandbox: bool = False) -> tuple[Path, list[str]]:
    """Re-run a ``swarmdeck run`` capsule's script as ``swarmdeck run`` ran it (``sandbox``: in the jail of
    ``swarmdeck run --sandbox``, the simulator and the safety filter on this side); the reproduced recording of the
    same Arena (``run.arena``) and notes."""
    from swarmdeck.console.recording.arena_recording import ArenaRecording
    from swarmdeck.console.runtime.config import read_obstacles
    from swarmdeck.devices.runner import ScriptError, run_experiment

    m = opened.manifest
    run = m.run
    script = opened.entry_path
    if script is None:
        raise CapsuleError("the capsule names no script to run (its manifest has no entry)")
    obstacles = None
    if run.get("obstacles"):
        obstacles = read_obstacles(opened.folder / str(run["obstacles"]))
    out = workdir / "reproduced.mcap"
    recording = ArenaRecording(out, script=script, seed=run.get("seed"), foxglove_channels=False)
    notes = []
    if run.get("robots_via"):
        notes.append("the run drove physical robots (--robots-via): the reproduction simulates them")
    try:
        if sandbox or run.get("sandbox"):
            notes += _rerun_sandboxed(opened, recording, obstacles)
        else:
            with params_in_environment(_params(run)):
                result = run_experiment(script, n_robots=run.get("robots"), duration=run.get("duration"),
                                        seed=run.get("seed"), safety=bool(run.get("safety", True)),
                                        rps=run.get("rps"), from_docks=bool(run.get("from_docks", False)),
                                        argv=list(run.get("argv") or []), obstacles=obstacles,
                                        rps_semantics=bool(run.get("rps_semantics", False)),
                                        rps_call_order=bool(run.get("rps_call_order", True)),
                                        robot_model=run.get("robot_model"), rps_generation=run.get("rps_generation"),
                                        on_create=recording.on_create, on_step=recording.on_step)
            if result.error_line:
                notes.append(f"the reproduced run raised: {result.error_line}")
    except (ScriptError, ValueError) as exc:
        notes.append(f"the reproduced run could not start: {exc}")
    finally:
        recording.close()
    k = int(run.get("arena", 0))
    if k >= len(recording.paths):
        raise CapsuleError(f"the reproduced run built {len(recording.paths)} Arena(s); the recording is of Arena {k + 1}")
    return recording.paths[k], notes


def _params(run: Mapping[str, Any]) -> dict[str, Any] | None:
    """The script's parameter values the capsule's run had (``run["params"]``; None: its defaults); CapsuleError
    for anything but a JSON object (a tampered capsule fails its hash first; this is for a hand-made one)."""
    values = run.get("params")
    if values is not None and not isinstance(values, dict):
        raise CapsuleError(f"the capsule's run params must be an object of parameter values, got {values!r}")
    return values


def _rerun_sandboxed(opened: OpenedCapsule, recording: Any, obstacles: Any) -> list[str]:
    """The capsule's script in the jail against a trusted Arena built as ``swarmdeck run --sandbox`` builds it,
    recorded by ``recording``; notes (how the script ended)."""
    from swarmdeck.console.sandbox.confinement import ConfinementUnavailable
    from swarmdeck.console.sandbox.plant import ArenaPlant
    from swarmdeck.console.sandbox.run import run_sandboxed
    from swarmdeck.core.robot_models import DEFAULT_ROBOT_MODEL, robot_params
    from swarmdeck.devices.arena import RUN_DEFAULTS, Arena, RunDefaults
    from swarmdeck.devices.rps.generation import robot_model_for
    from swarmdeck.devices.simulator import ArenaConfig

    run = opened.manifest.run
    script = opened.entry_path
    assert script is not None
    if run.get("from_docks"):
        raise CapsuleError("a run from the docks cannot be re-executed in the sandbox (swarmdeck run --from-docks "
                           "does not combine with --sandbox): re-run it without --sandbox")
    model = run.get("robot_model") or (
        "gternal" if run.get("rps_generation") == 2 else DEFAULT_ROBOT_MODEL if run.get("rps_generation") == 1
        else robot_model_for(script.read_text(encoding="utf-8", errors="replace")))
    config = ArenaConfig(seed=run.get("seed"), obstacles=obstacles)
    safety = bool(run.get("safety", True)) and not run.get("rps_semantics")

    def make_plant(n: int, initial: Any) -> Any:
        token = RUN_DEFAULTS.set(RunDefaults(on_create=recording.on_create, on_step=recording.on_step))
        try:
            arena = Arena(n, initial_conditions=initial, config=config, safety=safety, duration=run.get("duration"),
                          params=robot_params(model))
        finally:
            RUN_DEFAULTS.reset(token)
        return ArenaPlant(arena)

    try:
        outcome = run_sandboxed(script, make_plant, n_robots=run.get("robots"), duration=run.get("duration"),
                                rps=run.get("rps"), argv=list(run.get("argv") or []),
                                rps_semantics=bool(run.get("rps_semantics", False)),
                                rps_call_order=bool(run.get("rps_call_order", True)), robot_model=model,
                                rps_generation=run.get("rps_generation"), params=_params(run))
    except ConfinementUnavailable as exc:
        raise CapsuleError(f"cannot sandbox the capsule's script here: {exc}") from None
    return [f"the reproduced script ended: {outcome.error_line}"] if outcome.error_line else []


def reproduce(opened: OpenedCapsule, workdir: str | Path, *, sandbox: bool = False) -> Verdict:
    """Re-execute ``opened`` in simulation (module docstring) with scratch files in ``workdir``; its :class:`Verdict`.
    ``sandbox``: run a ``swarmdeck run`` capsule's script in the jail (a portal job's always runs there).
    CapsuleError for a capsule this swarmdeck cannot re-execute."""
    work = Path(workdir)
    m = opened.manifest
    env = tuple(environment_differences(m.environment, environment()))
    if m.kind == "run":
        reproduced, notes = _rerun_script(opened, work, sandbox)
        compared, n_a, n_b, first = compare_recordings(opened.recording, reproduced)
        return Verdict(compared, n_a, n_b, first, env, tuple(notes))
    if m.kind == "verification":  # one run of a sweep (console/sweep/capsules.py): its task again, recorded
        from swarmdeck.console.sweep.capsules import reproduce_task

        try:
            reproduced, notes = reproduce_task(opened, work)
        except ValueError as exc:
            raise CapsuleError(f"{opened.recording.name}: {exc}") from None
        compared, n_a, n_b, first = compare_recordings(opened.recording, reproduced)
        return Verdict(compared, n_a, n_b, first, env, tuple(notes))
    if m.kind in ("console", "portal"):
        return _resimulated(opened, env)
    raise CapsuleError(f"a capsule of kind {m.kind!r} cannot be re-executed by this swarmdeck")


def _resimulated(opened: OpenedCapsule, env: tuple[str, ...]) -> Verdict:
    from swarmdeck.console.recording.reader import open_recording
    from swarmdeck.console.recording.resimulate import resimulate

    notes: list[str] = []
    counts: dict[str, int] = {}
    with open_recording(opened.recording) as rec:
        total = rec.count_frames()
        if opened.manifest.kind == "portal":
            from swarmdeck.console.portal.reproduce import resimulate_job

            pairs: Iterable[tuple[Frame, Frame]] = resimulate_job(rec, opened, notes=notes, counts=counts)
        else:
            pairs = resimulate(rec, notes=notes)
        try:
            compared, first = compare_pairs(pairs)
        except ValueError as exc:
            raise CapsuleError(f"{opened.recording.name} cannot be re-simulated: {exc}") from None
        finally:
            close = getattr(pairs, "close", None)
            if close is not None:
                close()
        cfg = rec.config().get("config", {}) or {}
    if cfg.get("source", "simulation") != "simulation":
        notes.append(f"recorded with robots from {cfg.get('source')!r}: the reproduction's robots follow the model")
    # a difference stops the comparison, not the run; without one, the frames the reproduction made
    reproduced = counts.get("reproduced", compared) if first is None else total
    return Verdict(compared, total, reproduced, first, env, tuple(notes))


def print_verdict(verdict: Verdict, *, file: Any = None) -> None:
    """The verdict's summary on ``file`` (default stdout)."""
    print(verdict.summary(), file=file or sys.stdout)


__all__ = ["EXIT_DIFFERENT", "EXIT_ENVIRONMENT", "EXIT_IDENTICAL", "FirstDifference", "Verdict", "compare_pairs",
           "compare_recordings", "print_verdict", "reproduce"]
