"""The sandbox: what a script cannot do, asserted from the parent (real bubblewrap jail, real sockets, real files)."""
import os
import socket
import textwrap

import numpy as np
import pytest

from swarmdeck.console.sandbox.confinement import JAILS, JailConfig, SandboxLimits, choose_jail, processes_of
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.simulator import ArenaConfig


def plant(n, initial):
    return ArenaPlant(Arena(n, initial_conditions=initial, config=ArenaConfig(seed=1), duration=0.2))


@pytest.fixture(params=JAILS)
def run(request, tmp_path):
    """Runs a script body in the jail named by the parameter (each escape is tried in both jails)."""
    jail = JailConfig(order=(request.param,))
    if choose_jail(jail)[0] is None:
        pytest.skip(f"no {request.param} jail here: {choose_jail(jail)[1]}")

    def go(body, limits=SandboxLimits(), name="user"):
        folder = tmp_path / name
        folder.mkdir(exist_ok=True)
        script = folder / "script.py"
        script.write_text(textwrap.dedent(body))
        out = run_sandboxed(script, plant, n_robots=2, duration=0.2, limits=limits, jail=jail)
        assert out.jail == request.param
        return out

    return go


def test_no_connection_reaches_the_hosts_loopback(run, tmp_path):
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)
    server.setblocking(False)
    port = server.getsockname()[1]
    out = run(f"""
        import socket
        try:
            socket.create_connection(("127.0.0.1", {port}), timeout=2)
            print("CONNECTED")
        except OSError as exc:
            print("REFUSED", type(exc).__name__)
        def experiment(arena):
            arena.step()
    """)
    assert out.ok, out.error
    assert "REFUSED" in out.log and "CONNECTED" not in out.log
    with pytest.raises(BlockingIOError):
        server.accept()  # nothing ever arrived on the host's side
    server.close()


def test_files_outside_the_script_folder_are_invisible_and_nothing_outside_scratch_is_writable(run, tmp_path):
    lab = tmp_path / "lab"
    lab.mkdir()
    secret = lab / "secret.txt"
    secret.write_text("TOPSECRET")
    os.chmod(lab, 0o755)
    os.chmod(secret, 0o644)  # readable by anyone on the host: only the jail hides it
    repo_file = os.path.abspath("pyproject.toml")
    out = run(f"""
        import os
        for path in ({str(secret)!r}, {repo_file!r}, "/etc/passwd"):
            try:
                print("READ", path, open(path).read()[:20])
            except OSError as exc:
                print("NOREAD", path, type(exc).__name__)
        for path in (os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "dropped.txt"), {str(lab / "dropped.txt")!r},
                     "/usr/dropped.txt"):
            try:
                open(path, "w").write("x")
                print("WROTE", path)
            except OSError as exc:
                print("NOWRITE", path, type(exc).__name__)
        open("scratch_ok.txt", "w").write("fine")
        print("SCRATCH", open("scratch_ok.txt").read())
        def experiment(arena):
            arena.step()
    """)
    assert out.ok, out.error
    lines = out.log.splitlines()
    assert "TOPSECRET" not in out.log
    assert sum(line.startswith("NOREAD ") for line in lines) == 3 and not any(line.startswith("READ ") for line in lines)
    assert sum(line.startswith("NOWRITE ") for line in lines) == 3 and not any(line.startswith("WROTE ") for line in lines)
    assert "SCRATCH fine" in out.log
    assert not (tmp_path / "user" / "dropped.txt").exists() and not (lab / "dropped.txt").exists()
    assert not os.path.exists("/usr/dropped.txt")


def test_killing_the_parent_fails_and_the_run_reports_it(run, tmp_path):
    out = run(f"""
        import os, signal
        def experiment(arena):
            os.kill({os.getpid()}, signal.SIGKILL)
    """)
    assert out.ended_by == "error" and "ProcessLookupError" in out.error_line  # another pid namespace


def test_a_fork_bomb_ends_the_run_and_leaves_no_process(run, tmp_path):
    out = run("""
        import os
        def experiment(arena):
            while True:
                os.fork()
    """, SandboxLimits(processes=16, tick_s=2.0, max_overruns=2))
    assert not out.ok
    if out.uid is not None:  # root: the child had its own uid; none of its processes survived the run
        assert processes_of(out.uid) == []


def test_allocating_10_gb_is_a_memory_error_not_a_swarmdeck_crash(run, tmp_path):
    out = run("""
        def experiment(arena):
            block = bytearray(10 << 30)
    """)
    assert out.ended_by == "error" and "MemoryError" in out.error_line and "script.py:3" in out.error_line


def test_printing_100_mb_keeps_a_truncated_log(run, tmp_path):
    out = run("""
        import sys
        chunk = "x" * (1 << 20)
        for _ in range(100):
            sys.stdout.write(chunk)
        def experiment(arena):
            arena.step()
    """, SandboxLimits(log_bytes=4096))
    assert out.ok, out.error
    assert out.log_bytes >= 100 << 20
    assert len(out.log) < 4096 + 200 and "log truncated" in out.log


def test_an_endless_loop_at_import_ends_at_the_startup_limit(run, tmp_path):
    out = run("while True:\n    pass\n", SandboxLimits(startup_s=2.0))
    assert out.ended_by == "startup" and "import time" in out.error_line


@pytest.mark.parametrize("where", ["tick", "experiment"])
def test_an_endless_loop_in_a_tick_stops_the_robots_then_ends_the_run(run, where):
    body = {"tick": """
        import numpy as np
        def experiment(arena):
            for k in range(3):
                arena.set_velocities(np.full((arena.n, 2), 0.1))
                arena.step()
            while True:
                pass
    """, "experiment": """
        def experiment(arena):
            while True:
                pass
    """}[where]
    out = run(body, SandboxLimits(tick_s=0.3, max_overruns=3))
    assert out.ended_by == "overruns" and "per-tick compute budget" in out.error_line
    assert out.overruns == 3
    arena = out.plant.arena
    # the ticks the script missed were stopped ticks: the last command the robots got was zero
    assert np.all(arena.last_safe == 0.0)
