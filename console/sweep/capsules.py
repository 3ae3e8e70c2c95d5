"""One run of a sweep as a capsule (issue 31): recorded on request, reproduced by ``swarmdeck run run.zip``.

``swarmdeck sweep … --capsules`` records every run it runs (the sandboxed verification run of
:func:`~swarmdeck.console.sweep.runs.run_point`, frame by frame as ``swarmdeck play`` shows it) and writes
``DIR/capsules/KEY.zip`` beside its row ``DIR/runs/KEY.json``: a capsule of kind ``verification``
(:mod:`~swarmdeck.console.recording.capsule`) whose manifest's ``run`` holds everything the run is a function of —
the task (:func:`task_args`: mode, run index, the script's parameter values) and the whole
:class:`~swarmdeck.console.sandbox.verification.VerificationConfig` (:func:`config_dict`: duration, seed, robot count,
disturbances, limits, rules, jail, arena bounds, obstacles) — and the script files beside it.

``swarmdeck run KEY.zip`` (:func:`reproduce_task`, called by
:func:`~swarmdeck.console.recording.capsule_run.reproduce`) rebuilds that task from the manifest alone
(:func:`task_from_capsule`), runs it again in the sandbox with the same recording hooks and compares the two
recordings frame by frame, bit for bit. The sweep's own cache key is kept as ``run.sweep_key``.

Recordings are written where the run ran: with a Ray cluster, on the worker (its local disk), so ``--capsules`` is
for the local pool, or a cluster whose workers share ``DIR``.
"""
from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

from swarmdeck.console.recording.capsule import manifest_for
from swarmdeck.console.sandbox.bundle import ScriptBundle
from swarmdeck.console.sandbox.confinement import JailConfig, SandboxLimits
from swarmdeck.console.sandbox.plant import Disturbances
from swarmdeck.console.sandbox.verification import RunTask, VerificationConfig
from swarmdeck.core.bounds import check_bounds
from swarmdeck.core.obstacles import Obstacles
from swarmdeck.devices.validation import ValidationRules

#: The capsule kind of a sweep's run (a verification run of the script at one point of the design).
KIND = "verification"
#: Folder of ``DIR`` holding the runs' capsules (``KEY.zip``).
CAPSULES_DIR = "capsules"


def config_dict(cfg: VerificationConfig) -> dict[str, Any]:
    """Every field of ``cfg`` as JSON-able data (:func:`config_from_dict` reads it back to an equal config);
    unlike :meth:`VerificationConfig.to_dict` (a report's summary) it keeps ``rps``, ``declared_by``, the base
    ``limits`` and the whole jail configuration."""
    return {"n_robots": cfg.n_robots, "duration": float(cfg.duration), "runs": cfg.runs, "seed": cfg.seed,
            "bypass_threshold": float(cfg.bypass_threshold), "disturbances": asdict(cfg.disturbances),
            "limits": asdict(cfg.limits), "rules": asdict(cfg.rules), "trusted": cfg.trusted, "rps": cfg.rps,
            "jail": {**asdict(cfg.jail), "order": list(cfg.jail.order)},
            "initial_poses": None if cfg.initial_poses is None else [list(p) for p in cfg.initial_poses],
            "declared_by": cfg.declared_by, "wall_factor": float(cfg.wall_factor), "boot_s": float(cfg.boot_s),
            "paced_runs": cfg.paced_runs, "obstacles": None if cfg.obstacles is None else cfg.obstacles.to_list(),
            "bounds": [float(v) for v in cfg.bounds], "epsilon": cfg.epsilon, "confidence": float(cfg.confidence),
            "falsify_budget": cfg.falsify_budget}


def _table(d: Mapping[str, Any], key: str) -> dict[str, Any]:
    value = d.get(key)
    if not isinstance(value, Mapping):
        raise ValueError(f"capsule run.config.{key} must be an object, got {type(value).__name__}")
    return dict(value)


def config_from_dict(d: Any) -> VerificationConfig:
    """Inverse of :func:`config_dict`; ValueError naming the field that is missing or wrong."""
    if not isinstance(d, Mapping):
        raise ValueError(f"capsule run.config must be an object, got {type(d).__name__}")
    try:
        jail = _table(d, "jail")
        jail["order"] = tuple(jail.get("order") or ())
        poses = d.get("initial_poses")
        obstacles = d.get("obstacles")
        return VerificationConfig(
            n_robots=d.get("n_robots"), duration=d["duration"], runs=d["runs"], seed=d["seed"],
            bypass_threshold=d["bypass_threshold"], disturbances=Disturbances(**_table(d, "disturbances")),
            limits=SandboxLimits(**_table(d, "limits")), rules=ValidationRules(**_table(d, "rules")),
            trusted=bool(d["trusted"]), rps=d.get("rps"), jail=JailConfig(**jail),
            initial_poses=None if poses is None else tuple(tuple(p) for p in poses),
            declared_by=str(d.get("declared_by", "the manifest")), wall_factor=d["wall_factor"], boot_s=d["boot_s"],
            paced_runs=d["paced_runs"], obstacles=None if obstacles is None else Obstacles.of(obstacles),
            bounds=check_bounds(d["bounds"], "capsule run.config.bounds"), epsilon=d.get("epsilon"), confidence=d["confidence"],
            falsify_budget=d.get("falsify_budget", 0))
    except KeyError as exc:
        raise ValueError(f"capsule run.config is missing {exc.args[0]!r}") from None
    except TypeError as exc:
        raise ValueError(f"capsule run.config: {exc}") from None


def task_args(task: RunTask, *, sweep_key: str = "") -> dict[str, Any]:
    """The manifest's ``run`` of ``task``: ``mode``, ``index``, ``params`` (``{name: value}`` as the other capsule
    kinds write it, or None),
    ``config`` (:func:`config_dict`), ``seed`` (the config's: the capsule's key covers it) and ``sweep_key``."""
    params = None if task.params is None else dict(task.params)
    return {"mode": task.mode, "index": task.index, "params": params, "config": config_dict(task.config),
            "seed": task.config.seed, "sweep_key": sweep_key}


def task_from_capsule(run: Mapping[str, Any], files: Mapping[str, bytes], entry: str | None) -> RunTask:
    """The :class:`RunTask` a ``verification`` capsule describes (``run``: its manifest's ``run``; ``files``: the
    script files; ``entry``: the one that runs); ValueError naming what is wrong. Never a falsification run."""
    mode = run.get("mode")
    if mode not in ("raw", "wrapped"):
        raise ValueError(f"capsule run.mode must be 'raw' or 'wrapped', got {mode!r}")
    index = run.get("index")
    if isinstance(index, bool) or not isinstance(index, int) or index < 0:
        raise ValueError(f"capsule run.index must be an integer >= 0, got {index!r}")
    params = run.get("params")
    if isinstance(params, dict):  # the form every capsule kind writes
        params = list(params.items())  # JSON keeps the order it was written in
    elif params is not None and not (isinstance(params, list) and all(  # capsules written before 2026-11-27
            isinstance(p, list) and len(p) == 2 and isinstance(p[0], str) for p in params)):
        raise ValueError("capsule run.params must be an object of parameter values")
    if params is not None and not all(isinstance(k, str) for k, _ in params):
        raise ValueError("capsule run.params must be an object of parameter values")
    if entry is None:
        raise ValueError("the capsule names no entry script")
    bundle = ScriptBundle(entry, tuple(sorted(files.items())))
    return RunTask(bundle, config_from_dict(run.get("config")), index, mode,
                   params=None if params is None else tuple((k, v) for k, v in params))


def write_run_capsule(task: RunTask, recording: str | os.PathLike[str], out: str | os.PathLike[str], *,
                      sweep_key: str = "") -> Path:
    """The capsule zip of the recorded ``task`` (its recording at ``recording``) written to ``out``."""
    from swarmdeck.console.recording.capsule_zip import RecordedCapsule, write_capsule

    files = dict(task.bundle.files)
    manifest = manifest_for(KIND, files, entry=task.bundle.entry, run=task_args(task, sweep_key=sweep_key))
    return write_capsule(recording, out, capsule=RecordedCapsule(manifest, files))


def run_recorded(task: RunTask, capsule: str | os.PathLike[str], *, sweep_key: str = "") -> dict[str, Any]:
    """Run ``task`` (in the sandbox, as the sweep does) recording every step, write its capsule to ``capsule``
    (the recording goes inside it) and give the run's summary (:func:`run_task_plant`'s) and plant."""
    from swarmdeck.console.sandbox.verification import run_task_plant

    out = Path(capsule)
    out.parent.mkdir(parents=True, exist_ok=True)
    recording = out.with_name(out.stem + ".recording.mcap")
    try:
        result, plant = run_task_plant(replace(task, record=str(recording)))
        if result.get("ended_by") != "cancelled" and recording.exists():
            write_run_capsule(task, recording, out, sweep_key=sweep_key)
    finally:
        recording.unlink(missing_ok=True)
    return {"result": result, "plant": plant}


def reproduce_task(opened: Any, workdir: str | os.PathLike[str]) -> tuple[Path, list[str]]:
    """Run the task of the ``verification`` capsule ``opened`` (an
    :class:`~swarmdeck.console.recording.capsule_zip.OpenedCapsule`) again with its recording hooks; the path of the
    new recording (in ``workdir``) and notes. ValueError when the capsule does not describe a task."""
    from swarmdeck.console.sandbox.verification import run_task_plant

    m = opened.manifest
    files = {name: (opened.folder / name).read_bytes() for name in m.files}
    task = task_from_capsule(m.run, files, m.entry)
    out = Path(workdir) / "reproduced.mcap"
    result, _ = run_task_plant(replace(task, record=str(out)))
    notes = [] if result.get("error") is None else [f"the reproduced run failed as the script did: {result['error']}"]
    return out, notes


__all__ = ["CAPSULES_DIR", "KIND", "config_dict", "config_from_dict", "reproduce_task", "run_recorded", "task_args",
           "task_from_capsule", "write_run_capsule"]
