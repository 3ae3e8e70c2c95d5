"""Running a script body in each jail, for the jail-hardening suites.

The fixture ``jail_run`` is registered for every test by ``pytest_plugins`` in ``tests/conftest.py``; it is
parametrized over both jails ("unshare", "bwrap") and returns ``go(body, limits=…,
jail_options=…) -> SandboxOutcome`` (the body is dedented, runs with 2 robots for 0.2 s).
"""
import textwrap

import pytest

from swarmdeck.console.sandbox.confinement import JAILS, JailConfig, SandboxLimits, choose_jail
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.simulator import ArenaConfig


def plant(n, initial, duration=0.2):
    return ArenaPlant(Arena(n, initial_conditions=initial, config=ArenaConfig(seed=1), duration=duration))


@pytest.fixture(params=JAILS)
def jail_run(request, tmp_path):
    jail = JailConfig(order=(request.param,))
    if choose_jail(jail)[0] is None:
        pytest.skip(f"no {request.param} jail here: {choose_jail(jail)[1]}")

    def go(body, limits=SandboxLimits(), make_plant=plant, **jail_options):
        folder = tmp_path / f"run{len(list(tmp_path.iterdir()))}"
        folder.mkdir()
        script = folder / "script.py"
        script.write_text(textwrap.dedent(body))
        config = JailConfig(order=(request.param,), **jail_options)
        out = run_sandboxed(script, make_plant, n_robots=2, duration=0.2, limits=limits, jail=config)
        assert out.jail == request.param
        return out

    go.jail = request.param
    return go
