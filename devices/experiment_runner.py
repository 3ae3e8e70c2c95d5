"""Run a user's experiment script on the simulated arena and collect its report.

A script either defines ``experiment(arena)`` — the runner builds the
:class:`~swarmdeck.devices.Arena` (with ``--robots`` and ``--duration``) and
calls it — or is a plain rps-style script that builds its own ``Arena()``;
Arenas built without arguments take the runner's robot count and duration.
The run ends when the script returns or when the declared duration is over
(:class:`~swarmdeck.devices.ExperimentFinished`). A script that raises ends the
run with its traceback; the robots are stopped and the report still printed.
"""
from __future__ import annotations

import contextlib
import importlib.util
import re
import runpy
import sys
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from swarmdeck.devices.arena import RUN_DEFAULTS, Arena, ArenaReport, ExperimentFinished, RunDefaults
from swarmdeck.devices.rps import rps_aliases


class ScriptError(Exception):
    """The script could not be loaded (missing, unreadable, syntax error)."""


@dataclass
class RunResult:
    """What a run produced: the reports of every arena it built, and how it ended."""

    reports: list[ArenaReport] = field(default_factory=list)
    arenas: list[Arena] = field(default_factory=list)
    error: str | None = None  # formatted traceback of the script's own exception
    returned: Any = None

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


def _mentions_rps(source: str) -> bool:
    return re.search(r"^\s*(import rps\b|from rps\b)", source, re.MULTILINE) is not None


def run_experiment(
    target: str | Path | Callable[[Arena], Any],
    *,
    n_robots: int | None = None,
    duration: float | None = None,
    seed: int | None = None,
    safety: bool = True,
    on_step: Callable[[Arena], None] | None = None,
    rps: bool | None = None,
) -> RunResult:
    """Run a script file (or an ``experiment(arena)`` callable) and return its :class:`RunResult`.

    ``rps``: make ``import rps…`` resolve to swarmdeck's rps facade for this run;
    None (default) does so when the script mentions rps and no real rps is installed.
    """
    result = RunResult()
    defaults = RunDefaults(n_robots=n_robots, duration=duration, seed=seed, safety=safety,
                           on_create=result.arenas.append, on_step=on_step)
    token = RUN_DEFAULTS.set(defaults)
    try:
        try:
            if callable(target):
                result.returned = target(Arena())
            else:
                path = Path(target)
                source = _load(path)["source"]
                if rps is None:
                    rps = _mentions_rps(source) and importlib.util.find_spec("rps") is None
                sys.path.insert(0, str(path.parent.resolve()))
                try:
                    with rps_aliases() if rps else contextlib.nullcontext():
                        namespace = runpy.run_path(str(path), run_name="__swarmdeck_experiment__")
                        fn = namespace.get("experiment")
                        if callable(fn):
                            result.returned = fn(Arena())
                    if not callable(fn) and not result.arenas:
                        raise ScriptError(
                            f"{path} neither defines experiment(arena) nor creates an Arena at top level"
                        )
                finally:
                    sys.path.remove(str(path.parent.resolve()))
        except ExperimentFinished:
            pass
        except ScriptError:
            raise
        except Exception:  # the user's own code failed: report it, keep the data
            result.error = traceback.format_exc()
            for arena in result.arenas:
                arena.stop()
    finally:
        RUN_DEFAULTS.reset(token)
    result.reports = [a.report() for a in result.arenas]
    return result


def progress_bar(total_time: float | None) -> tuple[Callable[[Arena], None] | None, Callable[[], None]]:
    """An ``on_step`` callback drawing a tqdm bar on stderr when it is a terminal (else None)."""
    if total_time is None or not sys.stderr.isatty():
        return None, lambda: None
    from tqdm import tqdm

    bar = tqdm(total=round(total_time, 3), unit="s", desc="simulating", file=sys.stderr, leave=False)
    state = {"t": 0.0}

    def on_step(arena: Arena) -> None:
        t = min(arena.time, total_time)
        bar.update(round(t - state["t"], 3))
        state["t"] = t

    return on_step, bar.close
