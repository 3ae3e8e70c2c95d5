"""Simulation-based verification of untrusted experiment scripts (paper §IV-A, REFERENCE.md §2, §4).

For each script, ``runs`` simulated runs with the disturbances of a real arena
(:class:`~swarmdeck.console.sandbox.plant.Disturbances`), each run twice in the sandbox:

* **raw** — no barrier: measures the safety score S and the contacts (first
  contact time, approach speeds, contact durations, counts per robot);
* **wrapped** — the barrier on, as the experiment will run: must end without
  error, without any contact, and pass the Robotarium verifier's acceptance
  rules (more than 100 steps with robots too close or outside, simulated time
  above 1.5 × declared, N different from declared: rejected).

Verdicts: ``rejected`` (with the reasons), ``accepted`` (runs with the barrier),
``accepted, may bypass the barrier`` (every raw run clean, S ≥ the threshold in
every raw run, no contact at all, and — with an ``epsilon`` configured — the bound on
P(contact per run) at most ``epsilon``). Every script's report states that bound from its
raw runs (:mod:`.guarantee`: Clopper–Pearson, the rule of three when none had a contact):
"P(contact per run) ≤ 1.0 % at 95 % confidence (299 runs, 0 contacts)". Every run is a pure function of the
script's commands, the config and its index (:func:`run_task`), so any executor
gives the same report, bit for bit. The report's JSON schema is
``verification_report.schema.json`` beside this module (versioned by ``schema``).

**What runs is what the arena will run.** The script's Arena must have the declared
robot count (else it is refused at once, before anything is simulated), and every run
starts from the arena's start poses — the manifest's ``initial_poses``, else the
script's own initial conditions (checked like the manifest's), else random valid ones:
one rule, :func:`~swarmdeck.console.sandbox.start_poses.arena_start`, shared with the
arena runner — plus a seeded set-up error within the fleet's tolerance (2 cm, 5°).

**Nothing stalls it.** A missing, late or stale answer is a missed tick (robots stopped,
simulated time goes on; :mod:`.sandbox`), and every run has a wall-time budget derived
from the declared duration (:attr:`VerificationConfig.run_wall_s`: ``boot_s`` +
``wall_factor`` × duration), so a job's verification takes at most
``2 × runs × run_wall_s`` of worker time; a run that uses its budget up fails with that
reason.

**Pacing.** The first ``paced_runs`` raw runs tick in real time (one control period per
tick, as on the arena) instead of as fast as they compute, so a script cannot tell
verification from the arena by timing alone. Pacing changes when the script is asked,
never what is simulated: the trusted side is a function of the commands, so the verdict
of a script that behaves the same either way does not depend on the pacing. A script
can still find other ways to tell them apart; what keeps the arena safe is the guard
that watches every run without the barrier (docs/security.md), not this disguise.
"""
from __future__ import annotations

import math
import re
import time
from collections.abc import Callable, Mapping, Sequence
from contextlib import nullcontext
from dataclasses import asdict, dataclass, field, replace
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from swarmdeck.console.recording.arena_recording import ArenaRecording
from swarmdeck.console.sandbox.bundle import ScriptBundle
from swarmdeck.console.sandbox.cancel_file import CancelSeen, cancel_file
from swarmdeck.console.sandbox.confinement import JailConfig, SandboxLimits
from swarmdeck.console.sandbox.falsify import Probe
from swarmdeck.console.sandbox.guarantee import Guarantee
from swarmdeck.console.sandbox.plant import ArenaPlant, Disturbances, SandboxPlant, VerificationRobots, with_obstacles
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.console.sandbox.start_poses import arena_start, check_initial_poses, perturb
from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds, check_bounds
from swarmdeck.core.checks import in_range
from swarmdeck.core.kinematics import wrap_angle
from swarmdeck.core.obstacles import START_CLEARANCE, Obstacles
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.initial_conditions import random_initial_poses
from swarmdeck.devices.simulator import ArenaConfig, SimulatedArena
from swarmdeck.devices.validation import ValidationRules

SCHEMA = "swarmdeck.verification/1"
REJECTED, ACCEPTED, BYPASS = "rejected", "accepted", "accepted, may bypass the barrier"
SERIES_POINTS = 200  # minimum-distance samples kept per run in the report


@dataclass(frozen=True)
class VerificationConfig:
    """What a verification runs and how it decides.

    Attributes:
        n_robots: declared N: a script whose Arena asks for another count is refused at once (None: what
            the script builds — at most what fits in the arena — and an Arena built without a count gets 6;
            with ``initial_poses``, their count).
        duration: declared duration, s; every run ends there.
        runs: runs per script (each raw and wrapped).
        seed: base seed; run i uses the seed sequence (seed, i) for its initial conditions and disturbances.
        bypass_threshold: S every raw run must reach (with no contact at all) to bypass the barrier.
        disturbances: pose noise, latency, dropped commands.
        limits: the sandbox's limits per run (its ``wall_s`` is replaced by :attr:`run_wall_s`).
        rules: the Robotarium verifier's thresholds.
        trusted: run scripts unconfined where this machine cannot confine them.
        jail: which jails to try, in order (unshare, then bubblewrap).
        rps: resolve ``import rps`` to swarmdeck's facade (None: when no real rps is installed).
        initial_poses: the manifest's start poses ``(N, 3)`` [x, y, θ] (m, rad), as the arena will use
            them (None: the script's initial conditions, else random ones).
        declared_by: who declared ``n_robots``, for the refusal's message ("the manifest", "--robots").
        bounds: the arena the job will get, m: the floor, or its region of a shared floor as the script will see
            it (:attr:`swarmdeck.devices.fleet.regions.Region.local_bounds`) — the runs' walls, the random start
            poses and the script's ``arena.config.bounds`` are these.
        wall_factor: wall s each run may take per declared simulated s (above 1: paced runs tick in
            real time).
        boot_s: wall s each run may take on top for its start-up (jail, imports, the script's top level).
        paced_runs: raw runs (indices 0 … paced_runs − 1) that tick in real time, one control period
            per tick, like the arena.
        obstacles: the arena's line-segment obstacles (:class:`~swarmdeck.core.obstacles.Obstacles`), or None:
            solid in every run, kept clear by the barrier in the wrapped runs; a robot touching one is a contact
            (a wrapped run with one is rejected, a raw run with one refuses the bypass); start poses on them refused.
        epsilon: the largest P(contact per run) a bypass may have: the upper bound at ``confidence`` from the
            raw runs (REFERENCE.md §17) above it refuses the bypass (None: the bound is stated, not required).
        confidence: the confidence 1 − δ of the stated bound, in (0, 1).
        falsify_budget: runs the falsifier may spend per script searching the set-up errors and tracking offsets
            for the run closest to a contact (:mod:`.falsification`; 0: no search). Never counted in the bound.
    """

    n_robots: int | None = None
    duration: float = 30.0
    runs: int = 8
    seed: int = 0
    bypass_threshold: float = 0.99
    disturbances: Disturbances = field(default_factory=Disturbances)
    limits: SandboxLimits = field(default_factory=SandboxLimits)
    rules: ValidationRules = field(default_factory=ValidationRules)
    trusted: bool = False
    rps: bool | None = None
    jail: JailConfig = field(default_factory=JailConfig)
    initial_poses: tuple[tuple[float, float, float], ...] | None = None
    declared_by: str = "the manifest"
    wall_factor: float = 4.0
    boot_s: float = 30.0
    paced_runs: int = 1
    obstacles: Obstacles | None = None
    bounds: Bounds = DEFAULT_BOUNDS
    epsilon: float | None = None
    confidence: float = 0.95
    falsify_budget: int = 0

    def __post_init__(self) -> None:
        if not in_range(self.falsify_budget, 0, integer=True):
            raise ValueError(f"falsify_budget must be a non-negative integer number of runs, got {self.falsify_budget!r}")
        Guarantee(1, 0, self.confidence, self.epsilon)  # ValueError naming a bad confidence or epsilon
        object.__setattr__(self, "bounds", check_bounds(self.bounds, "bounds"))
        if self.obstacles is not None:
            object.__setattr__(self, "obstacles", ArenaConfig(obstacles=self.obstacles, bounds=self.bounds).obstacles)
        if self.n_robots is not None and not in_range(self.n_robots, 1, integer=True):
            raise ValueError(f"n_robots must be a positive integer, got {self.n_robots!r}")
        if not in_range(self.duration, 0.0, lo_open=True):
            raise ValueError(f"duration must be a finite number of seconds > 0, got {self.duration!r}")
        if not in_range(self.runs, 1, integer=True):
            raise ValueError(f"runs must be a positive integer, got {self.runs!r}")
        if not in_range(self.seed, 0, integer=True):
            raise ValueError(f"seed must be a non-negative integer, got {self.seed!r}")
        if not in_range(self.bypass_threshold, 0.0, 1.0):
            raise ValueError(f"bypass_threshold must be in [0, 1], got {self.bypass_threshold!r}")
        if not in_range(self.wall_factor, 1.0, lo_open=True):
            raise ValueError(f"wall_factor must be a number > 1 (wall s per simulated s), got {self.wall_factor!r}")
        if not in_range(self.boot_s, 0.0, lo_open=True):
            raise ValueError(f"boot_s must be a number of seconds > 0, got {self.boot_s!r}")
        if not in_range(self.paced_runs, 0, integer=True):
            raise ValueError(f"paced_runs must be a non-negative integer, got {self.paced_runs!r}")
        if self.initial_poses is not None:
            n = self.n_robots if self.n_robots is not None else len(self.initial_poses)
            poses = check_initial_poses(self.initial_poses, n, self.bounds, "initial_poses")
            object.__setattr__(self, "initial_poses", tuple((float(x), float(y), float(t)) for x, y, t in poses))
            object.__setattr__(self, "n_robots", n)
            if self.obstacles is not None:
                self.obstacles.check_clear(poses, START_CLEARANCE, "start pose")

    @property
    def run_wall_s(self) -> float:
        """Wall-time budget of one sandboxed run, s: ``boot_s`` + ``wall_factor`` × ``duration``."""
        return float(self.boot_s + self.wall_factor * self.duration)

    def job_wall_s(self, scripts: int = 1) -> float:
        """The most worker time a verification of ``scripts`` scripts can take, s (every run at its budget)."""
        searched = self.falsify_budget + 1 if self.falsify_budget else 0  # the search and the worst case's replay
        return (2 * self.runs + searched) * scripts * self.run_wall_s

    @property
    def run_limits(self) -> SandboxLimits:
        """The sandbox limits of one run: ``limits`` with its wall time the run's budget."""
        return replace(self.limits, wall_s=self.run_wall_s)

    def to_dict(self) -> dict:
        return {"n_robots": self.n_robots, "duration": float(self.duration), "runs": self.runs, "seed": self.seed,
                "bypass_threshold": float(self.bypass_threshold), "disturbances": self.disturbances.to_dict(),
                "limits": asdict(self.run_limits), "rules": asdict(self.rules), "trusted": self.trusted,
                "jail": list(self.jail.order), "allow_no_cgroup": self.jail.allow_no_cgroup,
                "initial_poses": None if self.initial_poses is None else [list(p) for p in self.initial_poses],
                "paced_runs": self.paced_runs, "bounds": list(self.bounds),
                "epsilon": self.epsilon, "confidence": float(self.confidence),
                **({} if self.obstacles is None else {"obstacles": self.obstacles.to_list()}),
                **({"falsify_budget": self.falsify_budget} if self.falsify_budget else {}),
                "wall_budget": {"factor": float(self.wall_factor), "boot_s": float(self.boot_s),
                                "run_s": self.run_wall_s, "job_s": self.job_wall_s()}}


@dataclass(frozen=True)
class RunTask:
    """One sandboxed run: the script's text travels with the task (so remote workers need no shared disk)."""

    bundle: ScriptBundle
    config: VerificationConfig
    index: int
    mode: str  # "raw", "wrapped" or "falsify" (a searched run: raw, from ``probe``)
    cancel_path: str | None = None  # the run stops when this file exists
    probe: Probe | None = None  # a searched run's set-up error and tracking offset (mode "falsify")
    record: str | None = None  # record the run to this MCAP file (the worst case's replay)
    #: the script's parameter values (``swarmdeck.devices.params``; a sweep's point), None: its defaults
    params: tuple[tuple[str, Any], ...] | None = None

    @property
    def paced(self) -> bool:
        """The run ticks in real time (the first ``paced_runs`` raw runs): it mostly waits for the clock, so the
        executors run it beside the computing runs instead of in one of their workers' turns (executors.py)."""
        return self.mode == "raw" and self.index < self.config.paced_runs


def load_script(path: str | Path | ScriptBundle, entry: str | None = None) -> ScriptBundle:
    """The files of a script to verify: a ``.py`` file, or a directory with its ``entry`` file
    (default ``main.py``), or a bundle as it is; ValueError naming what is wrong."""
    if isinstance(path, ScriptBundle):
        return path
    try:
        return ScriptBundle.from_path(path, entry)
    except OSError as exc:
        raise ValueError(f"cannot read the script {str(path)!r}: {exc}") from exc


def _series(values: list[float]) -> list[float]:
    if len(values) <= SERIES_POINTS:
        return [round(v, 6) for v in values]
    idx = np.linspace(0, len(values) - 1, SERIES_POINTS).round().astype(int)
    return [round(values[i], 6) for i in idx]


def run_task(task: RunTask) -> dict[str, Any]:
    """Run one task in the sandbox and summarise it as a JSON-ready dict (the same on any executor)."""
    return run_task_plant(task)[0]


def run_task_plant(task: RunTask) -> tuple[dict[str, Any], SandboxPlant | None]:
    """:func:`run_task`'s summary and the run's plant (None: the script built no Arena), for callers that measure
    more of the run's end (``console/sweep``); the plant stays in the worker."""
    cfg = task.config
    # (seed, index): 0 random start poses, 1 disturbances, 2 set-up error — raw and wrapped of one index alike;
    # a searched run starts from run 0's start poses plus its probe, with disturbances of its own stream
    searched = task.mode == "falsify"
    if searched and task.probe is None:
        raise ValueError("a searched run needs its probe")
    seeds = np.random.SeedSequence(cfg.seed, spawn_key=(0 if searched else task.index,)).spawn(3)
    if searched:
        seeds[1] = np.random.SeedSequence(cfg.seed, spawn_key=(FALSIFY_STREAM, task.index))
    paced = task.paced
    # paced: each step waits for the next period
    arena_config = ArenaConfig(seed=None, real_time=paced, obstacles=cfg.obstacles, bounds=cfg.bounds)
    rules = cfg.rules
    start: dict[str, Any] = {}

    def random_poses(n: int) -> np.ndarray:
        return random_initial_poses(n, arena_config.bounds, rng=np.random.default_rng(seeds[0]),
                                    obstacles=arena_config.segments)

    def make_plant(n: int, initial: np.ndarray | None, obstacles: np.ndarray | None = None) -> SandboxPlant:
        nonlocal arena_config  # the script's own obstacles (rps 2.x) are solid beside the lab's: random starts avoid them
        if obstacles is not None:
            arena_config = replace(arena_config, obstacles=with_obstacles(arena_config, obstacles))
        chosen = arena_start(n, cfg.n_robots, cfg.initial_poses, initial, random_poses, arena_config.bounds,
                             declared_by=cfg.declared_by)
        if arena_config.obstacles is not None:  # the script's own initial conditions too
            arena_config.obstacles.check_clear(chosen.poses, START_CLEARANCE, "start pose")
        if task.probe is not None:
            poses = np.array(chosen.poses, dtype=float) + np.array(task.probe.setup, dtype=float).reshape(n, 3)
            poses[:, 2] = wrap_angle(poses[:, 2])
        else:
            poses = perturb(chosen.poses, np.random.default_rng(seeds[2]))
        start.update(source=chosen.source, poses=poses)
        sim = SimulatedArena(n, poses, config=arena_config, rules=rules)
        robots = VerificationRobots(sim, cfg.disturbances, np.random.default_rng(seeds[1]), contact_distance=sim.params.diameter,
                                    offset=None if task.probe is None else np.array(task.probe.offset, dtype=float))
        arena = Arena(backend=robots, config=arena_config, safety=task.mode == "wrapped", duration=cfg.duration)
        if task.record is None:
            return ArenaPlant(arena)
        return recorded_plant(arena, recording.setdefault("hooks", ArenaRecording(
            task.record, script=task.bundle.entry, seed=cfg.seed, foxglove_channels=False)))

    recording: dict[str, ArenaRecording] = {}
    cancel_path = task.cancel_path
    cancelled = CancelSeen(cancel_path) if cancel_path else None
    cpu0 = time.process_time()  # this worker's CPU (the trusted side: plant, barrier, protocol) for the run
    outcome = run_sandboxed(task.bundle, make_plant, n_robots=cfg.n_robots,
                            duration=cfg.duration, rps=cfg.rps, limits=cfg.run_limits, trusted=cfg.trusted,
                            jail=cfg.jail, cancelled=cancelled,
                            bounds=None if cfg.bounds == DEFAULT_BOUNDS else cfg.bounds,
                            params=None if task.params is None else dict(task.params))
    recorded = recording["hooks"].close() if "hooks" in recording else []
    error = outcome.error_line
    if outcome.ended_by == "wall":
        reached = "" if outcome.plant is None else f" at t = {outcome.plant.arena.time:.2f} s of {cfg.duration:g} s"
        error = (f"the run used up its verification budget of {cfg.run_wall_s:g} s wall time ({cfg.boot_s:g} s "
                 f"start-up + {cfg.wall_factor:g} × the declared {cfg.duration:g} s){reached}: the script is too slow")
    result: dict[str, Any] = {
        "index": task.index, "mode": task.mode, "ended_by": outcome.ended_by, "error": error,
        "n_robots": outcome.n_robots, "ticks": outcome.ticks, "overruns": outcome.overruns,
        "log": outcome.log[-4000:], "log_bytes": outcome.log_bytes, "paced": paced,
        "cgroup": outcome.cgroup, "unhardened": outcome.unhardened,
        "start_poses_from": start.get("source"),
        "start_poses": [[round(float(v), 6) for v in row] for row in start["poses"][:50]] if start else None,
        # CPU s of the run, trusted side and jail: what the portal charges to the researcher's daily limit
        "cpu_s": round(time.process_time() - cpu0 + (outcome.child_cpu_s or 0.0), 3),
    }
    if task.record is not None:
        result["recorded"] = recorded
    if outcome.metrics:  # the script's own (record_metrics): only when it recorded any
        result["metrics"] = dict(outcome.metrics)
    plant = outcome.plant
    if plant is None:
        result.update(time=0.0, safety_score=None, contacts=None, min_distance=None, min_distance_series=[],
                      contact_points=[], validation=None, safety_filter=None, invalid_commands=0,
                      rule_violations=[])
        return result, None
    robots: VerificationRobots = plant.arena.backend
    contacts = robots.contacts.report(plant.arena.params.max_speed, robots.true_poses[:, :2])
    report = plant.arena.report().to_dict()
    result.update(
        time=round(plant.arena.time, 9),
        safety_score=contacts.score,
        contacts={"count": len(contacts.contacts), "first_time": contacts.first_contact_time,
                  "mean_approach_speed": contacts.mean_approach_speed,
                  "mean_duration_s": contacts.mean_contact_duration_s,
                  "per_robot": [int(c) for c in contacts.contacts_per_robot]},
        min_distance=min(robots.min_distance) if robots.min_distance else None,
        min_distance_series=_series(robots.min_distance),
        contact_points=[[round(t, 6), round(x, 6), round(y, 6)] for t, x, y in robots.contact_points[:50]],
        validation=report["validation"], safety_filter=report["safety"], invalid_commands=report["invalid_commands"],
        rule_violations=robots.report.verdict(cfg.duration, rules),
        obstacle_contact_steps=int(robots.report.steps_with_obstacle_contact),
    )
    if searched or task.record is not None:
        result["closest"] = closest_of(robots, result)
    return result, plant


#: the first spawn-key entry of the searched runs' disturbance streams (raw runs use (index,) and its children)
FALSIFY_STREAM = 2**31


def closest_of(robots: VerificationRobots, result: dict[str, Any]) -> dict[str, Any]:
    """The closest approach of a run as the report gives it: clearance m (0 at a contact), kind ("robots",
    "obstacle" or "" when nothing came near), the two robots or the robot and the segment, and when (s)."""
    c = robots.closest
    touched = bool(result["contacts"] and result["contacts"]["count"]) or bool(result.get("obstacle_contact_steps"))
    clearance = 0.0 if touched else (None if not math.isfinite(c.clearance) else round(max(c.clearance, 0.0), 9))
    entry: dict[str, Any] = {"clearance": clearance, "kind": c.kind, "time": round(c.time, 6)}
    if c.kind == "robots":
        entry["robots"] = [c.first, c.second]
    elif c.kind == "obstacle":
        entry.update(robot=c.first, segment=c.second)
    if touched and result["contacts"] and result["contacts"]["first_time"] is not None:
        entry["contact_time"] = result["contacts"]["first_time"]
    return entry


def recorded_plant(arena: Arena, recording: ArenaRecording) -> SandboxPlant:
    """The plant on ``arena`` with every tick recorded (the worst case's replay, ``swarmdeck play``)."""
    plant = ArenaPlant(arena)
    recording.on_create(arena)

    def step(nominal: np.ndarray | None) -> None:
        plant.apply(nominal)
        recording.on_step(arena)

    return SandboxPlant(plant.n, plant.observe, step, plant.finished, arena)


def _run_reasons(run: dict[str, Any], cfg: VerificationConfig) -> list[str]:
    """Why this run fails the acceptance rules (empty: it passes)."""
    reasons = []
    if run["error"] is not None:
        reasons.append(run["error"])
    reasons.extend(run.get("rule_violations") or [])
    if run["safety_filter"] is not None and run["invalid_commands"]:
        reasons.append(f"the script sent {run['invalid_commands']} non-finite (NaN/inf) robot commands (robots stopped)")
    if run["mode"] == "wrapped" and run["contacts"] and run["contacts"]["count"]:
        reasons.append(f"robots touched {run['contacts']['count']} times with the barrier on")
    if run["mode"] == "wrapped" and run.get("obstacle_contact_steps"):
        reasons.append(f"robots touched obstacles in {run['obstacle_contact_steps']} steps with the barrier on")
    return reasons


#: the sandbox's per-run folder in a message (``/tmp/swarmdeck-script-k1z…/``): random, so it would make one error
#: look like as many errors as runs, and it tells the researcher nothing
_RUN_FOLDER = re.compile(r"(?:/[^\s:'\"()]*)?/swarmdeck-script-[A-Za-z0-9_]+/")
_FILE_LINE = re.compile(r"(?<![\w./-])([\w./-]+\.py)(?::|\"?, line )(\d+)")


def without_run_folder(text: str) -> str:
    """``text`` without the sandbox's per-run folder (``/tmp/swarmdeck-script-…/``): file names stay relative."""
    return _RUN_FOLDER.sub("", text)


def _excerpt(bundle: ScriptBundle, name: str, line: int) -> str | None:
    """Line ``line`` (1-based) of file ``name`` of the bundle, stripped (None: no such line)."""
    try:
        text = dict(bundle.files)[name].decode("utf-8", "replace").splitlines()
    except KeyError:
        return None
    return text[line - 1].strip()[:160] if 1 <= line <= len(text) and text[line - 1].strip() else None


def user_message(text: str | None, bundle: ScriptBundle, shown: str | None = None) -> str | None:
    """A run's error as the researcher should read it: without the sandbox's random run folder, the entry called
    ``shown`` (the file name the researcher uploaded; the portal stores it under another name), and the
    first line of their code it names quoted: ``spin.py:3 (in experiment): KeyError: 'oops' — line 3:
    raise KeyError('oops')``. The same error in every run then reads the same (and is reported once)."""
    if text is None:
        return None
    text = _RUN_FOLDER.sub("", text)
    shown = shown or bundle.entry
    if shown != bundle.entry:
        text = re.sub(rf"(?<![\w./-]){re.escape(bundle.entry)}(?![\w-])", shown, text)
    for m in _FILE_LINE.finditer(text):
        name = bundle.entry if m.group(1) == shown else m.group(1)
        line = _excerpt(bundle, name, int(m.group(2)))
        if line is not None:
            return f"{text} — line {m.group(2)}: {line}"
    return text


def compile_check(bundle: ScriptBundle, shown: str | None = None) -> str | None:
    """Compile the entry script before anything runs: why it cannot run (a syntax error, with its line and an
    excerpt), or None. Costs no sandbox run; the source is bounded by the bundle's size limit."""
    try:
        compile(bundle.source, bundle.entry, "exec", dont_inherit=True)
    except SyntaxError as exc:
        where = "" if exc.lineno is None else f" at line {exc.lineno}"
        line = None if exc.lineno is None else _excerpt(bundle, bundle.entry, exc.lineno)
        return (f"syntax error in {shown or bundle.entry}{where}: {exc.msg}" + ("" if line is None else f" — {line}")
                + " (found by compiling the script: nothing was run)")
    except ValueError as exc:  # null bytes
        return f"the script cannot be compiled: {exc} (nothing was run)"
    except (MemoryError, RecursionError):  # the parser's own bound: expressions nested tens of thousands deep
        return ("the script cannot be compiled: it nests expressions deeper than Python's parser allows "
                "(nothing was run)")
    return None


def _rejected_unrun(bundle: ScriptBundle, shown: str, reason: str) -> dict[str, Any]:
    """The report entry of a script refused before any run (:func:`compile_check`)."""
    return {"script": shown, "sha256": bundle.sha256, "verdict": REJECTED, "safety_score": None,
            "safety_score_min": None, "safety_score_ci95": None, "reasons": [reason], "bypass_refused_because": [],
            "contact_bound": None, "runs": []}


def _grouped(pairs: list[tuple[int, str]]) -> list[str]:
    """'reason (runs 0, 2)' lines, in order of first appearance."""
    by_reason: dict[str, list[int]] = {}
    for index, reason in pairs:
        by_reason.setdefault(reason, []).append(index)
    return [f"{reason} (run{'s' if len(ix) > 1 else ''} {', '.join(map(str, ix))})" for reason, ix in by_reason.items()]


def guarantee(raw: Sequence[dict[str, Any]], cfg: VerificationConfig) -> Guarantee | None:
    """The stated bound on P(contact per run) from the raw runs (None: no raw run). A raw run with a contact, or
    that measured nothing (it ended before the plant existed), or that touched an obstacle segment, counts as a
    contact: the bound never flatters."""
    if not raw:
        return None
    failed = sum(1 for r in raw if not r.get("contacts") or r["contacts"]["count"] > 0
                 or (r.get("obstacle_contact_steps") or 0) > 0)
    return Guarantee(len(raw), failed, cfg.confidence, cfg.epsilon)


def script_verdict(bundle: ScriptBundle, runs: Sequence[dict[str, Any]], cfg: VerificationConfig,
                   shown: str | None = None, falsification: dict[str, Any] | None = None) -> dict[str, Any]:
    """The verdict of one script from its raw and wrapped runs (ordered by index); ``shown``: what to call the
    entry in messages (the researcher's file name; default the entry's). ``falsification``: the falsifier's
    entry (:func:`~swarmdeck.console.sandbox.falsification.falsify_script`), reported beside the bound (which
    it never enters); a contact it found refuses the bypass."""
    runs = [dict(r, error=user_message(r["error"], bundle, shown), log=_RUN_FOLDER.sub("", r.get("log") or ""))
            for r in runs]
    wrapped = [r for r in runs if r["mode"] == "wrapped"]
    raw = [r for r in runs if r["mode"] == "raw"]
    reasons = _grouped([(r["index"], why) for r in wrapped for why in _run_reasons(r, cfg)])
    scores = [r["safety_score"] for r in raw if r["safety_score"] is not None]
    score = float(np.mean(scores)) if scores else None
    no_bypass: list[str] = []
    if not reasons:
        no_bypass = _grouped([(r["index"], why) for r in raw for why in _run_reasons(r, cfg)])
        low = [r["index"] for r in raw if r["safety_score"] is None or r["safety_score"] < cfg.bypass_threshold]
        touched = sum(r["contacts"]["count"] for r in raw if r["contacts"])
        on_obstacles = sum(r.get("obstacle_contact_steps") or 0 for r in raw)
        if low:
            no_bypass.append(f"S below {cfg.bypass_threshold:g} without the barrier in runs {', '.join(map(str, low))}")
        if touched:
            no_bypass.append(f"{touched} contacts without the barrier")
        if on_obstacles:
            no_bypass.append(f"robots touched obstacles in {on_obstacles} steps without the barrier")
    bound = guarantee(raw, cfg)
    if not reasons and bound is not None and (short := bound.shortfall()) is not None:
        no_bypass.append(short)
    if not reasons and falsification is not None and falsification.get("found_contact"):
        worst = falsification["worst_case"]
        replay = f"; replay {falsification['recording']}" if falsification.get("recording") else ""
        no_bypass.append(f"the falsifier found a contact without the barrier within the set-up tolerance: "
                         f"{worst['where']} "
                         f"(searched run {worst['run']} of {falsification['runs']}{replay})")
    verdict = REJECTED if reasons else (BYPASS if not no_bypass else ACCEPTED)
    spread = None
    if score is not None and len(scores) >= 2:
        half = 1.96 * float(np.std(scores, ddof=1)) / math.sqrt(len(scores))
        spread = [max(0.0, score - half), min(1.0, score + half)]
    return {
        "script": shown or bundle.name, "sha256": bundle.sha256, "verdict": verdict,
        "safety_score": score, "safety_score_min": min(scores) if scores else None, "safety_score_ci95": spread,
        "reasons": reasons, "bypass_refused_because": no_bypass if verdict == ACCEPTED else [],
        "contact_bound": None if bound is None else bound.to_dict(),
        **({} if falsification is None else {"falsification": falsification}),
        "runs": list(runs),
    }


def _falsify(bundle: ScriptBundle, runs: Sequence[dict[str, Any]], entry: dict[str, Any], config: VerificationConfig,
             executor: Any, cancel_path: str, cancelled: Callable[[], bool], record_dir: str | Path | None,
             cpu: list[float], on_done: Callable[[RunTask, dict[str, Any], int], None],
             record_name: str | None = None, params: tuple[tuple[str, Any], ...] | None = None) -> dict[str, Any]:
    """The falsifier's entry of one script (:mod:`.falsification`): skipped for a rejected script or one whose raw
    runs never built an Arena; VerificationCancelled when cancelled meanwhile. ``params``: the runs' parameter
    values (as :attr:`RunTask.params`)."""
    from swarmdeck.console.sandbox.falsification import SearchCancelled, falsify_script, skipped

    if entry["verdict"] == REJECTED:
        return skipped("the script is rejected", config.falsify_budget)
    n = next((r["n_robots"] for r in runs if r["mode"] == "raw" and r.get("n_robots")), None)
    if n is None:
        return skipped("no raw run built an Arena", config.falsify_budget)

    def run_batch(batch: Sequence[RunTask]) -> list[dict[str, Any] | None]:
        results = executor.run(batch, lambda k, r, f: on_done(batch[k], r, f), cancelled)
        cpu[0] += sum(float(r.pop("cpu_s", 0.0)) for r in results if r is not None)
        return results

    try:
        return falsify_script(bundle, config, int(n), run_batch, cancel_path, record_dir, record_name, params)
    except SearchCancelled as exc:
        raise VerificationCancelled("verification was cancelled", cpu[0]) from exc


@dataclass
class VerificationReport:
    """The outcome of :func:`verify`: one entry per script and the overall verdict."""

    config: VerificationConfig
    scripts: list[dict[str, Any]]
    executor: str = "serial"
    cpu_s: float = 0.0  # CPU s of every run, trusted side and jail (not in the JSON: it is a timing)

    @property
    def verdict(self) -> str:
        """The worst verdict over the scripts."""
        order = [REJECTED, ACCEPTED, BYPASS]
        return min((s["verdict"] for s in self.scripts), key=order.index)

    @property
    def safety_score(self) -> float | None:
        """The lowest mean S over the scripts."""
        scores = [s["safety_score"] for s in self.scripts if s["safety_score"] is not None]
        return min(scores) if scores else None

    @property
    def accepted(self) -> bool:
        return self.verdict != REJECTED

    def to_dict(self) -> dict[str, Any]:
        """The JSON report (schema ``swarmdeck.verification/1``; no timings, so equal runs give equal JSON)."""
        return {"schema": SCHEMA, "verdict": self.verdict, "safety_score": self.safety_score,
                "reasons": [r if s["script"] in r else f"{s['script']}: {r}"  # named once
                            for s in self.scripts for r in s["reasons"]],
                "config": self.config.to_dict(), "scripts": self.scripts}


class VerificationCancelled(Exception):
    """:func:`verify` was cancelled before every run finished; ``cpu_s``: the CPU its runs used until then."""

    def __init__(self, message: str, cpu_s: float = 0.0) -> None:
        super().__init__(message)
        self.cpu_s = float(cpu_s)


@dataclass(frozen=True)
class Progress:
    """Passed to the progress callback after each finished run."""

    done: int
    total: int
    script: str
    index: int
    mode: str


def verify(scripts: Sequence[str | Path | ScriptBundle], config: VerificationConfig = VerificationConfig(),
           executor: Any = None, *, on_progress: Callable[[Progress], None] | None = None,
           cancel: Any = None, entry: str | None = None,
           names: Sequence[str | None] | None = None,
           worst_case_dir: str | Path | None = None, worst_case_name: str | None = None,
           params: Mapping[str, Any] | None = None) -> VerificationReport:
    """Verify ``scripts`` under ``config`` on ``executor`` (default: a local process pool).

    ``on_progress(Progress)`` is called after each run; ``cancel`` is a
    :class:`threading.Event` (or anything with ``is_set()``): once set, runs not yet finished
    are stopped and :class:`VerificationCancelled` is raised. ``scripts``: ``.py`` files,
    directories (each run from its ``entry`` file, default ``main.py``, with sibling modules
    importable) or :class:`~swarmdeck.console.sandbox.bundle.ScriptBundle`\\ s. ValueError for a
    script that cannot be read or an invalid bundle; :class:`~swarmdeck.console.sandbox.confinement.ConfinementUnavailable` when
    this machine cannot confine untrusted code and ``config.trusted`` is False. ``names``: what to call each
    script's entry in the report (the file names the researcher uploaded; default the entries' own).

    Each entry script is compiled first (:func:`compile_check`): one that does not compile is rejected with its
    line and an excerpt, without any sandbox run.

    With ``config.falsify_budget`` > 0, every script not rejected is then searched for its worst case
    (:mod:`.falsification`, on the same executor); ``worst_case_dir``: where its recording is kept
    (``worst_case_name``, default ``<entry stem>-worst-case.mcap``; None: not recorded).

    ``params``: the scripts' parameter values (``swarmdeck.devices.params``; None: their defaults), the same in
    every run — raw, wrapped and searched.
    """
    from swarmdeck.console.sandbox.confinement import ConfinementUnavailable, probe
    from swarmdeck.console.sandbox.executors import LocalPoolExecutor

    loaded = [load_script(s, entry) for s in scripts]
    if not loaded:
        raise ValueError("no script to verify")
    shown = [b.name if names is None or k >= len(names) or not names[k] else str(names[k])
             for k, b in enumerate(loaded)]
    unrunnable = {k: why for k, b in enumerate(loaded) if (why := compile_check(b, shown[k])) is not None}
    if len(unrunnable) == len(loaded):  # nothing to run: no jail needed, no sandbox run spent
        return VerificationReport(config, [_rejected_unrun(b, shown[k], unrunnable[k]) for k, b in enumerate(loaded)],
                                  "none (compile check)", 0.0)
    reason = probe(config.jail)
    if reason is not None and not config.trusted:
        raise ConfinementUnavailable(f"cannot confine untrusted code on this machine: {reason}; "
                                     "pass --trusted to run it unconfined")
    executor = executor if executor is not None else LocalPoolExecutor()
    runnable = [k for k in range(len(loaded)) if k not in unrunnable]
    with cancel_file(cancel, "swarmdeck-verification-cancel") as (cancel_path, cancelled):
        values = None if params is None else tuple(sorted(dict(params).items()))
        tasks = [RunTask(loaded[k], config, i, mode, cancel_path, params=values)
                 for k in runnable for i in range(config.runs) for mode in ("raw", "wrapped")]

        total = len(tasks) + config.falsify_budget * len(runnable)
        searched_done = [0]

        def done(k: int, result: dict[str, Any], finished: int) -> None:
            if on_progress is not None:
                t = tasks[k]
                on_progress(Progress(finished, total, t.bundle.name, t.index, t.mode))

        def done_searched(name: str, task: RunTask, result: dict[str, Any], finished: int) -> None:
            searched_done[0] += 1
            if on_progress is not None:
                on_progress(Progress(len(tasks) + searched_done[0], total, name, task.index, task.mode))

        searched_cpu = [0.0]
        kept = getattr(executor, "kept", None)  # with a search: one pool for the runs and every generation
        with kept() if kept is not None and config.falsify_budget else nullcontext():
            results = executor.run(tasks, done, cancelled)
            cpu_s = sum(float(r.pop("cpu_s", 0.0)) for r in results if r is not None)  # a timing: not in the report
            if (cancel is not None and cancel.is_set()) or any(r is None or r["ended_by"] == "cancelled" for r in results):
                raise VerificationCancelled("verification was cancelled", cpu_s)
            searched_cpu[0] = cpu_s  # the searched runs' CPU adds to it
            reports = []
            for k, bundle in enumerate(loaded):
                if k in unrunnable:
                    reports.append(_rejected_unrun(bundle, shown[k], unrunnable[k]))
                    continue
                s = runnable.index(k)
                runs = results[s * 2 * config.runs : (s + 1) * 2 * config.runs]
                verdict = script_verdict(bundle, runs, config, shown[k])
                if config.falsify_budget:
                    found = _falsify(bundle, runs, verdict, config, executor, cancel_path, cancelled, worst_case_dir,
                                     searched_cpu, partial(done_searched, shown[k]), worst_case_name, values)
                    verdict = script_verdict(bundle, runs, config, shown[k], found)
                reports.append(verdict)
    return VerificationReport(config, reports, getattr(executor, "name", type(executor).__name__), searched_cpu[0])
