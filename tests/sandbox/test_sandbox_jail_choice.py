"""Which jail confines a script: unshare (the fork server) or bubblewrap, the fallback between them,
a refusal with the reason when none works, and a fresh jail for every script."""
import os
import sys
import textwrap

import pytest

from swarmdeck.console.sandbox.confinement import (
    ConfinementUnavailable,
    JailConfig,
    choose_jail,
    probe_bwrap,
    probe_unshare,
)
from swarmdeck.console.sandbox.executors import SerialExecutor
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.console.sandbox.verification import VerificationConfig, verify
from swarmdeck.console.sandbox.zygote import shared_fork_server
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.simulator import ArenaConfig

MISSING = "/nonexistent/bwrap"
needs_unshare = pytest.mark.skipif(probe_unshare() is not None, reason=f"no namespaces here: {probe_unshare()}")
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


def script(tmp_path, body=SCRIPT, name="s.py"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(body))
    return path


@needs_unshare
def test_without_bubblewrap_the_unshare_jail_is_used(tmp_path):
    jail = JailConfig(order=("bwrap", "unshare"), bwrap=MISSING)
    assert choose_jail(jail) == ("unshare", None)
    out = run_sandboxed(script(tmp_path), plant, n_robots=2, duration=0.3, jail=jail)
    assert out.ok, out.error
    assert out.jail == "unshare" and out.ticks > 0


@needs_bwrap
def test_bubblewrap_can_be_asked_for(tmp_path):
    out = run_sandboxed(script(tmp_path), plant, n_robots=2, duration=0.3, jail=JailConfig(order=("bwrap",)))
    assert out.ok, out.error
    assert out.jail == "bwrap" and out.ticks > 0


def test_where_no_jail_works_untrusted_code_is_refused_with_the_reason(tmp_path):
    jail = JailConfig(order=("bwrap",), bwrap=MISSING)
    with pytest.raises(ConfinementUnavailable, match="bwrap.*not installed.*--trusted"):
        run_sandboxed(script(tmp_path), plant, n_robots=2, duration=0.3, jail=jail)
    config = VerificationConfig(n_robots=2, duration=0.3, runs=1, jail=jail)
    with pytest.raises(ConfinementUnavailable, match="not installed"):
        verify([script(tmp_path)], config, SerialExecutor())
    # --trusted: runs unconfined, and says so
    out = run_sandboxed(script(tmp_path), plant, n_robots=2, duration=0.3, jail=jail, trusted=True)
    assert out.ok and out.jail is None


def test_a_jail_order_names_known_jails_once():
    for order in ((), ("docker",), ("bwrap", "bwrap")):
        with pytest.raises(ValueError, match="jail order"):
            JailConfig(order=order)


@needs_bwrap
def test_cli_jail_option(tmp_path, capsys):
    import json

    from swarmdeck.console.cli import main

    path = script(tmp_path)
    assert main(["verify", str(path), "--jail", "bwrap", "--runs", "1", "--duration", "0.3", "--robots", "2",
                 "--workers", "1", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["config"]["jail"] == ["bwrap"]
    with pytest.raises(SystemExit) as exit_:
        main(["verify", str(path), "--jail", "sideways"])
    assert exit_.value.code == 2 and "--jail" in capsys.readouterr().err


@needs_unshare
def test_every_script_gets_a_fresh_jail_and_process_image(tmp_path):
    # the first script leaves marks everywhere it can: a module attribute, a new module, its scratch folder
    first = script(tmp_path, """
        import numpy, sys, os, types
        numpy.LEFT_BEHIND = "first"
        sys.modules["left_behind"] = types.ModuleType("left_behind")
        open("mark.txt", "w").write("first")
        print("SCRATCH", os.getcwd())
        def experiment(arena):
            arena.step()
    """, "first.py")
    second = script(tmp_path, """
        import numpy, sys, os
        print("ATTR", getattr(numpy, "LEFT_BEHIND", None), "MODULE", "left_behind" in sys.modules)
        print("SCRATCH", os.getcwd(), sorted(os.listdir(".")))
        print("FIRST", os.path.exists(os.path.join(os.path.dirname(os.getcwd()), "mark.txt")))
        def experiment(arena):
            arena.step()
    """, "second.py")
    jail = JailConfig(order=("unshare",))
    a = run_sandboxed(first, plant, n_robots=2, duration=0.3, jail=jail)
    b = run_sandboxed(second, plant, n_robots=2, duration=0.3, jail=jail)
    assert a.ok and b.ok, (a.error, b.error)
    assert "ATTR None MODULE False" in b.log
    scratch_a = a.log.split("SCRATCH ")[1].split()[0]
    assert f"SCRATCH {scratch_a}" not in b.log and "SCRATCH" in b.log and "[]" in b.log
    assert not os.path.exists(scratch_a)  # the scratch folder went with the run


@needs_unshare
def test_a_dead_fork_server_is_replaced(tmp_path):
    server = shared_fork_server()
    server.proc.kill()
    server.proc.wait()
    out = run_sandboxed(script(tmp_path), plant, n_robots=2, duration=0.3, jail=JailConfig(order=("unshare",)))
    assert out.ok, out.error
    assert shared_fork_server() is not server


@needs_bwrap
def test_an_interpreter_path_through_a_folder_the_jail_lacks_still_runs(tmp_path, monkeypatch):
    """Bubblewrap runs the interpreter by its normalised path: started as ``…/bench/../.venv/bin/python``, the jail
    has no ``bench/`` folder and execvp failed before the fix (every run "ended unexpectedly (exit status 1)")."""
    outside = tmp_path / "not_in_the_jail"
    outside.mkdir()
    detour = os.path.join(str(outside), *[".."] * len(outside.parts[1:]), sys.executable.lstrip("/"))
    assert os.path.samefile(detour, sys.executable) and ".." in detour
    monkeypatch.setattr(sys, "executable", detour)
    out = run_sandboxed(script(tmp_path), plant, n_robots=2, duration=0.3, jail=JailConfig(order=("bwrap",)))
    assert out.ok, (out.error, out.log)
    assert out.jail == "bwrap" and out.ticks > 0
