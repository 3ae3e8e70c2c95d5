"""The jail binds every top-level swarmdeck package: its list cannot drift from pyproject.toml's
(the network and sensing packages were each forgotten once, and every bubblewrap-jailed script
importing them crashed), and a bubblewrap-jailed script can import them."""
import textwrap
import tomllib
from pathlib import Path

import pytest

from swarmdeck.console.sandbox.confinement import (
    SWARMDECK_PACKAGES,
    JailConfig,
    _system_paths,
    probe_bwrap,
)
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.simulator import ArenaConfig

ROOT = Path(__file__).resolve().parents[2]
needs_bwrap = pytest.mark.skipif(probe_bwrap() is not None, reason=f"no bubblewrap here: {probe_bwrap()}")


def top_level_packages() -> set[str]:
    packages = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"]
    return {name.split(".")[1] for name in packages if name.startswith("swarmdeck.")}


def test_the_bound_packages_are_pyprojects_top_level_packages():
    assert set(SWARMDECK_PACKAGES) == top_level_packages()
    assert len(SWARMDECK_PACKAGES) == len(set(SWARMDECK_PACKAGES))
    assert {"sensing", "network"} <= set(SWARMDECK_PACKAGES)


def test_every_packages_folder_is_bound():
    import importlib

    bound = _system_paths()
    for name in SWARMDECK_PACKAGES:
        folder = Path(importlib.import_module(f"swarmdeck.{name}").__file__).resolve().parent
        assert any(folder.is_relative_to(p) for p in bound), name


SCRIPT = """
import numpy as np
import swarmdeck.network
import swarmdeck.sensing
def experiment(arena):
    while True:
        arena.set_velocities(np.zeros((arena.n, 2)))
        arena.step()
"""


def plant(n, initial):
    return ArenaPlant(Arena(n, initial_conditions=initial, config=ArenaConfig(seed=3), duration=0.2))


@needs_bwrap
def test_a_bubblewrap_jailed_script_imports_sensing_and_network(tmp_path):
    path = tmp_path / "s.py"
    path.write_text(textwrap.dedent(SCRIPT))
    out = run_sandboxed(path, plant, n_robots=2, duration=0.2, jail=JailConfig(order=("bwrap",)))
    assert out.ok, out.error
    assert out.jail == "bwrap" and out.ticks > 0
