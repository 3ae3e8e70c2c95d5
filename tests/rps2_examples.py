"""The Robotarium Python simulator's own examples (tests/data/rps2_examples: rps 2.0 ``master/`` and the earlier
``dev/`` branch, unchanged) run under swarmdeck as a user runs them: a copy of the example's folder as the working
directory (they open files beside them and save data there), the script run by :func:`run_experiment` — what
``swarmdeck run SCRIPT --duration S`` runs — shortened with ``duration`` where the example runs long, never edited.

Shared by tests/devices/test_devices_rps2_examples.py, tests/devices/test_devices_rps2_examples_sensors.py and
bench/bench_rps2_examples.py.
"""
from __future__ import annotations

import contextlib
import io
import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from swarmdeck.devices.runner import RunResult, run_experiment

EXAMPLES = Path(__file__).parent / "data" / "rps2_examples"

#: rps 2.x's ``debug()`` verdicts (rps/robotarium.py on master), the accepting ones
DEBUG_ACCEPTED = ("No errors or warnings in your simulation!  Your script will run on the Robotarium!",
                  "No hard errors detected, your script will run on the Robotarium!")
DEBUG_HEAD = "Your simulation took approximately"


@dataclass
class ExampleRun:
    """One example's run: the runner's result, what the script printed, the poses when its Robotarium was built
    and at the end ((N, 3) rows), and the folder it ran in."""

    result: RunResult
    output: str
    start: np.ndarray
    end: np.ndarray
    folder: Path
    arenas: list[Any] = field(default_factory=list)

    @property
    def report(self) -> Any:
        (report,) = self.result.reports
        return report


def run_example(name: str, workdir: Path, duration: float | None = None, seed: int = 1, **kw: Any) -> ExampleRun:
    """Run example ``name`` (a path under tests/data/rps2_examples, e.g. ``"master/go_to_goal/go_to_point_si.py"``)
    from a copy of its folder in ``workdir``, for at most ``duration`` simulated seconds."""
    source = EXAMPLES / name
    folder = workdir / Path(name).parent  # its folders too: they are rps.examples' packages to the script
    shutil.copytree(source.parent, folder)
    starts: list[np.ndarray] = []
    out = io.StringIO()
    cwd = os.getcwd()
    np.random.seed(seed)  # the examples draw their goals from numpy's global generator, as under rps
    try:
        os.chdir(folder)
        with contextlib.redirect_stdout(out):
            result = run_experiment(folder / source.name, duration=duration, seed=seed,
                                    on_create=lambda arena: starts.append(arena.poses().copy()), **kw)
    finally:
        os.chdir(cwd)
    end = result.arenas[0].poses().copy() if result.arenas else np.zeros((0, 3))
    start = starts[0] if starts else np.zeros((0, 3))
    return ExampleRun(result, out.getvalue(), start, end, folder, list(result.arenas))
