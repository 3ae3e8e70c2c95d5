"""Run a user's experiment script on the simulated arena and collect its report.

A script either defines ``experiment(arena)`` — the runner builds the
:class:`~swarmdeck.devices.Arena` (with ``--robots`` and ``--duration``) and
calls it — or is a plain rps-style script that builds its own ``Arena()``;
Arenas built without arguments take the runner's robot count and duration.
The run ends when the script returns or when the declared duration is over
(:class:`~swarmdeck.devices.ExperimentFinished`). A script that raises ends the
run: the robots are stopped, the report is still produced, and the error is kept
both as one line naming the script's own line (:attr:`RunResult.error_line`) and
as the full traceback (:attr:`RunResult.error`). ``sys.exit()`` / ``sys.exit(0)``
in a script ends the run normally; a non-zero exit is reported as an error.
Arenas the runner builds itself (``experiment(arena)``) are built outside the
script's error handling, so a bad ``--robots`` is a plain :class:`ValueError`.
"""
from __future__ import annotations

import contextlib
import dataclasses
import importlib.util
import re
import runpy
import sys
import threading
import traceback
import types
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from swarmdeck.core.errors import SwarmdeckError
from swarmdeck.core.robot_models import robot_params
from swarmdeck.devices.arena import RUN_DEFAULTS, Arena, ArenaReport, ExperimentFinished, RunDefaults
from swarmdeck.devices.fleet.setup import SetupFailed
from swarmdeck.devices.rps import rps_aliases
from swarmdeck.devices.rps.generation import script_generation


class ScriptError(SwarmdeckError):
    """The script could not be loaded (missing, unreadable, syntax error)."""


class RunnerArenaError(ValueError, SwarmdeckError):
    """The runner could not build the Arena it hands to ``experiment(arena)`` (e.g. too many robots)."""


def _runner_arena() -> Arena:
    try:
        return Arena()
    except ValueError as exc:
        raise RunnerArenaError(str(exc)) from exc


@dataclass
class RunResult:
    """What a run produced: the reports of every arena it built, and how it ended."""

    reports: list[ArenaReport] = field(default_factory=list)
    arenas: list[Arena] = field(default_factory=list)
    error: str | None = None  # formatted traceback of the script's own exception
    error_line: str | None = None  # the same in one line: "script.py:12 (in f): ValueError: …"
    returned: Any = None
    notes: list[str] = field(default_factory=list)  # compatibility provided for the script (e.g. np.mat)
    interrupted: bool = False  # Ctrl-C (or SIGTERM) ended the run; the reports cover what ran

    @property
    def ok(self) -> bool:
        return self.error is None


def _load(path: Path) -> dict:
    if not path.is_file():
        raise ScriptError(f"experiment script {str(path)!r} does not exist or is not a file")
    try:
        source = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ScriptError(f"cannot read experiment script {str(path)!r}: {exc}") from exc
    try:
        compile(source, str(path), "exec")
    except SyntaxError as exc:
        raise ScriptError(f"syntax error in {path}:{exc.lineno}: {exc.msg}") from exc
    return {"source": source}


def describe_error(exc: BaseException, script: str | None = None) -> str:
    """One line for a script's exception: where in the script it happened, its type and message.

    The location is the innermost frame in ``script`` (the file the user wrote), else the
    innermost frame outside swarmdeck, else the innermost frame.
    """
    frames = traceback.extract_tb(exc.__traceback__)
    mine = [f for f in frames if script is not None and Path(f.filename).resolve() == Path(script).resolve()]
    if not mine:
        package = str(Path(__file__).resolve().parents[1])
        mine = [f for f in frames if not str(Path(f.filename).resolve()).startswith(package)
                and not f.filename.startswith("<frozen")] or frames
    where = f"{Path(mine[-1].filename).name}:{mine[-1].lineno} (in {mine[-1].name}): " if mine else ""
    text = " ".join(str(exc).split()) or "(no message)"
    return f"{where}{type(exc).__name__}: {text}"


def run_as_main(path: Path, source: str) -> dict[str, Any]:
    """Run a script's ``source`` (read from ``path``) as ``python path`` runs it, ``__name__ == "__main__"``;
    returns its globals.

    In the main thread through :func:`runpy.run_path`: the script is ``sys.modules["__main__"]`` while it runs,
    exactly as under ``python``. In any other thread (several scripts at once: the regions of a shared floor, a
    portal's runners) in a module of its own that is never registered: ``sys.modules["__main__"]`` is one per
    process, and runpy's save-and-restore of it from two threads at once left the first script registered as the
    process's main for good (a later ``multiprocessing`` spawn then ran that script in every child it started,
    and a verification pool waited for its workers forever).
    """
    if threading.current_thread() is threading.main_thread():
        return runpy.run_path(str(path), run_name="__main__")
    module = types.ModuleType("__main__")
    module.__dict__.update(__file__=str(path), __cached__=None, __loader__=None, __package__="", __spec__=None)
    exec(compile(source, str(path), "exec"), module.__dict__)  # noqa: S102 - the user's own script, as python runs it
    return dict(module.__dict__)


def _nothing_runnable(path: Path, source: str) -> str:
    """Why a script that ran to its end gave nothing to run: what was looked for, and what it has."""
    text = (f"{path} ran as __main__ (as `python {path.name}` runs it) but neither defines experiment(arena) "
            "nor built an Arena or rps Robotarium")
    if re.search(r"^if\s+__name__\s*==\s*['\"]__main__['\"]\s*:", source, re.MULTILINE):
        text += ("; it has an `if __name__ == \"__main__\":` block, which ran: does the code there return "
                 "before building one (e.g. on its command-line arguments, given after the script name)?")
    return text


def run_experiment(
    target: str | Path | Callable[[Arena], Any],
    *,
    n_robots: int | None = None,
    duration: float | None = None,
    seed: int | None = None,
    safety: bool = True,
    on_step: Callable[[Arena], None] | None = None,
    rps: bool | None = None,
    backend_factory: Callable[..., Any] | None = None,
    on_create: Callable[[Arena], None] | None = None,
    from_docks: bool = False,
    argv: Sequence[str] = (),
    rps_semantics: bool = False,
    rps_call_order: bool = True,
    obstacles: Any = None,
    bounds: Any = None,
    robot_model: str | None = None,
    rps_generation: int | None = None,
) -> RunResult:
    """Run a script file (or an ``experiment(arena)`` callable) and return its :class:`RunResult`.

    ``rps``: make ``import rps…`` resolve to swarmdeck's rps facade for this run;
    None (default) does so when no real rps is installed.
    ``backend_factory``: builds the robots of Arenas the script creates (see
    :class:`~swarmdeck.devices.arena.RunDefaults`); None: the simulated arena.
    ``on_create``: called with every Arena the run builds.
    ``from_docks``: the simulated robots start docked on the chargers, are set up to the script's
    initial poses before its first step and are returned to the chargers after it (also when it
    failed: they are stopped first); a return that does not finish is added to ``notes``.
    ``argv``: the script's command-line arguments (``sys.argv[1:]`` while it runs; ``sys.argv[0]`` is
    the script). A script file runs as ``__main__``, as ``python script.py`` runs it; ``experiment(arena)``
    is then called unless the script built its own Arena already.
    ``rps_semantics``/``rps_call_order``: the rps facade's modes (:class:`~swarmdeck.devices.rps.robotarium.Robotarium`).
    ``obstacles``: line-segment obstacles (:class:`~swarmdeck.core.obstacles.Obstacles`) of every Arena the
    script builds without its own.
    ``bounds``: the arena ``(x_min, x_max, y_min, y_max)`` (m) Arenas and Robotariums the script builds without a
    config see (its region of a shared floor, :mod:`swarmdeck.devices.fleet.floor`); None: the default floor.
    ``robot_model``: the robots of Arenas built without params (:mod:`swarmdeck.core.robot_models`; None: the
    GRITSBot, and for the rps facade the model of the script's generation). ``rps_generation``: 1 or 2, the rps
    the script was written for (None: read from its source, :func:`~swarmdeck.devices.rps.generation.script_generation`).
    """
    if robot_model is not None:
        robot_params(robot_model)  # a bad name is the caller's error, named before anything runs
    if rps_generation not in (None, 1, 2):
        raise ValueError(f"rps_generation must be 1 or 2 (rps 1.x or 2.x), got {rps_generation!r}")
    result = RunResult()

    def created(arena: Arena) -> None:
        result.arenas.append(arena)
        if on_create is not None:
            on_create(arena)

    defaults = RunDefaults(n_robots=n_robots, duration=duration, seed=seed, safety=safety,
                           on_create=created, on_step=on_step, backend_factory=backend_factory,
                           from_docks=from_docks, rps_semantics=rps_semantics, rps_call_order=rps_call_order,
                           obstacles=obstacles, bounds=bounds, robot_model=robot_model, rps_generation=rps_generation)
    token = RUN_DEFAULTS.set(defaults)
    script = None if callable(target) else str(target)
    try:
        try:
            if callable(target):
                result.returned = target(_runner_arena())
            else:
                path = Path(target)
                source = _load(path)["source"]
                if rps_generation is None:
                    RUN_DEFAULTS.set(dataclasses.replace(defaults, rps_generation=script_generation(source)))
                if rps is None:  # also for scripts that import rps only through their own modules (MARBLER)
                    rps = importlib.util.find_spec("rps") is None
                sys.path.insert(0, str(path.parent.resolve()))
                saved_argv = sys.argv
                sys.argv = [str(path), *argv]  # as `python script.py ARGS…` sees them
                try:
                    aliases: contextlib.AbstractContextManager[list[str]] = (
                        rps_aliases(path.parent.resolve()) if rps else contextlib.nullcontext([]))
                    with aliases as notes:
                        result.notes = notes  # the facade adds to it while the script runs
                        # as `python script.py` runs it: code under `if __name__ == "__main__":` runs too
                        namespace = run_as_main(path, source)
                        fn = namespace.get("experiment")
                        if callable(fn) and not result.arenas:
                            result.returned = fn(_runner_arena())
                    if not callable(fn) and not result.arenas:
                        raise ScriptError(_nothing_runnable(path, source))
                finally:
                    sys.argv = saved_argv
                    sys.path.remove(str(path.parent.resolve()))
        except ExperimentFinished:
            pass
        except KeyboardInterrupt:  # the user stopped the run: stop the robots, keep the reports
            result.interrupted = True
            for arena in result.arenas:
                arena.stop()
        except SystemExit as exc:  # sys.exit() in a script ends the run, not swarmdeck
            if exc.code not in (None, 0):
                result.error = f"the script called sys.exit({exc.code!r})"
                result.error_line = f"{Path(script or '?').name}: called sys.exit({exc.code!r})"
        except Exception as exc:  # the user's own code failed: report it, keep the data
            if isinstance(exc, (ScriptError, RunnerArenaError)):
                raise
            result.error = traceback.format_exc()
            result.error_line = describe_error(exc, script)
        if result.error is not None:
            for arena in result.arenas:
                arena.stop()
    finally:
        RUN_DEFAULTS.reset(token)
    _return_fleets(result)
    result.reports = [a.report() for a in result.arenas]
    return result


def _return_fleets(result: RunResult) -> None:
    """Dock the robots of every Arena that started from the chargers (after the script, safely)."""
    for arena in result.arenas:
        if arena.fleet is None or arena.fleet.assignment is None:
            continue
        try:
            arena.return_to_chargers()
        except SetupFailed as exc:
            result.notes.append(f"return to the chargers failed: {exc}")


def progress_bar(total_time: float | None) -> tuple[Callable[[Arena], None] | None, Callable[[], None]]:
    """An ``on_step`` callback drawing a tqdm bar on stderr when it is a terminal (else None).

    With a ``total_time`` (s) a bar to it; without one (a run until the script ends or Ctrl-C) a
    counter of simulated seconds with the simulation rate, so an open-ended run shows it is alive.
    """
    if not sys.stderr.isatty():
        return None, lambda: None
    from tqdm import tqdm

    total = None if total_time is None else round(total_time, 3)
    desc = "simulating" if total is not None else "simulating (Ctrl-C stops and prints the report)"
    bar = tqdm(total=total, unit="s", desc=desc, file=sys.stderr, leave=False,
               bar_format=None if total is not None else "{desc}: {n:.1f} s simulated [{elapsed}, {rate_fmt}]")
    return _Progress(bar, total_time), bar.close


class _Progress:
    """The progress bar's per-step callback: it reads the Arena's time, not its annotations
    (:attr:`Arena.annotations_read`)."""

    reads_annotations = False

    def __init__(self, bar: Any, total_time: float | None) -> None:
        self.bar, self.total_time, self.t = bar, total_time, 0.0

    def __call__(self, arena: Arena) -> None:
        t = arena.time if self.total_time is None else min(arena.time, self.total_time)
        self.bar.update(round(t - self.t, 3))
        self.t = t
