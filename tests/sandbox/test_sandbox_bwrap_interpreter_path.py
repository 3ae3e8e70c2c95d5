"""Bubblewrap runs the interpreter by a normalised path: started as ``…/bench/../.venv/bin/python`` (a benchmark
run from ``bench/``, a user's relative path), the jail has no ``bench/`` folder, and execvp failed with "No such file
or directory" before the fix — every bwrap-jailed run of such a process ended "unexpectedly (exit status 1)"."""
import os
import sys
import textwrap

import pytest

from swarmdeck.console.sandbox.confinement import JailConfig, probe_bwrap
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.simulator import ArenaConfig

needs_bwrap = pytest.mark.skipif(probe_bwrap() is not None, reason=f"no bubblewrap here: {probe_bwrap()}")

SCRIPT = """
import numpy as np
def experiment(arena):
    while True:
        arena.set_velocities(np.full((arena.n, 2), 0.05))
        arena.step()
"""


def plant(n, initial):
    return ArenaPlant(Arena(n, initial_conditions=initial, config=ArenaConfig(seed=3), duration=0.3))


@needs_bwrap
def test_an_interpreter_path_through_a_folder_the_jail_lacks_still_runs(tmp_path, monkeypatch):
    outside = tmp_path / "not_in_the_jail"
    outside.mkdir()
    detour = os.path.join(str(outside), *[".."] * len(outside.parts[1:]), sys.executable.lstrip("/"))
    assert os.path.samefile(detour, sys.executable) and ".." in detour
    monkeypatch.setattr(sys, "executable", detour)
    path = tmp_path / "s.py"
    path.write_text(textwrap.dedent(SCRIPT))
    out = run_sandboxed(path, plant, n_robots=2, duration=0.3, jail=JailConfig(order=("bwrap",)))
    assert out.ok, (out.error, out.log)
    assert out.jail == "bwrap" and out.ticks > 0
