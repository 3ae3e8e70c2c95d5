"""Multi-file experiments: a directory with an entry file runs in the jail, its sibling modules import,
its files are read-only, nothing beside it is visible; bad bundles are refused with the reason."""
import os
import textwrap

import pytest

from swarmdeck.console.sandbox.bundle import MAX_BYTES, ScriptBundle
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.console.sandbox.verification import VerificationConfig, verify
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.simulator import ArenaConfig

confined = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")


def plant(n, initial):
    return ArenaPlant(Arena(n, initial_conditions=initial, config=ArenaConfig(seed=2), duration=0.3))


def experiment_dir(tmp_path):
    root = tmp_path / "exp"
    (root / "lib").mkdir(parents=True)
    (root / "main.py").write_text(textwrap.dedent(f"""
        from pathlib import Path
        import helpers
        from lib.gains import GAIN

        def experiment(arena):
            here = Path(__file__).parent
            print("PARAM", (here / "params.txt").read_text().strip())
            try:
                (here / "written.txt").write_text("x")
                print("WROTE-OWN-FOLDER")
            except OSError as exc:
                print("READ-ONLY", type(exc).__name__)
            outside = Path({str(tmp_path / "secret.txt")!r})  # beside the directory on this machine
            print("SEES-OUTSIDE" if outside.exists() else "OUTSIDE-HIDDEN")
            while True:
                arena.set_velocities(helpers.towards_centre(arena.positions(), GAIN))
                arena.step()
    """))
    (root / "helpers.py").write_text("def towards_centre(p, k):\n    return -k * (p - p.mean(axis=0))\n")
    (root / "lib" / "__init__.py").write_text("")
    (root / "lib" / "gains.py").write_text("GAIN = 0.5\n")
    (root / "params.txt").write_text("spacing=0.3\n")
    (tmp_path / "secret.txt").write_text("not for the script")
    return root


@confined
def test_a_directory_runs_with_sibling_modules_read_only_and_alone(tmp_path):
    root = experiment_dir(tmp_path)
    out = run_sandboxed(root, plant, n_robots=3, duration=0.3)
    assert out.ok, out.error
    assert out.ended_by == "duration" and out.ticks > 0
    assert "PARAM spacing=0.3" in out.log
    assert "READ-ONLY" in out.log and "WROTE-OWN-FOLDER" not in out.log
    assert "OUTSIDE-HIDDEN" in out.log
    assert not (root / "written.txt").exists()


@confined
def test_another_entry_file_of_the_directory_can_be_named(tmp_path):
    root = experiment_dir(tmp_path)
    (root / "alt.py").write_text("import helpers\nfrom lib import gains\nprint('ALT', gains.GAIN)\n"
                                 "from swarmdeck.devices import Arena\nArena(2).step()\n")
    out = run_sandboxed(root, plant, entry="alt.py", n_robots=2, duration=0.3)
    assert out.ok, out.error
    assert "ALT 0.5" in out.log and "PARAM" not in out.log  # main.py did not run


@confined
def test_verify_takes_a_directory_and_names_its_entry(tmp_path):
    root = experiment_dir(tmp_path)
    config = VerificationConfig(n_robots=3, duration=0.3, runs=1, seed=0)
    report = verify([root], config, SerialExecutor()).to_dict()
    script = report["scripts"][0]
    assert script["script"] == "main.py" and script["verdict"] != "rejected", script["reasons"]
    assert script["sha256"] == ScriptBundle.from_path(root).sha256
    assert all(r["error"] is None for r in script["runs"])


def test_a_single_file_bundle_keeps_the_scripts_own_digest(tmp_path):
    import hashlib

    script = tmp_path / "one.py"
    script.write_bytes(b"print(1)\n")
    bundle = ScriptBundle.from_path(script)
    assert bundle.entry == "one.py" and bundle.sha256 == hashlib.sha256(b"print(1)\n").hexdigest()


def test_changing_any_file_changes_the_digest(tmp_path):
    root = experiment_dir(tmp_path)
    before = ScriptBundle.from_path(root).sha256
    (root / "lib" / "gains.py").write_text("GAIN = 0.6\n")
    assert ScriptBundle.from_path(root).sha256 != before


@pytest.mark.parametrize("name", ["../evil.py", "/etc/passwd", "a/../../b.py", "", "a//b.py", "./x.py", "a\\b.py",
                                  "x\x00.py", "a/"])
def test_names_that_could_leave_the_folder_are_refused(name):
    with pytest.raises(ValueError, match="bundle|relative|name"):
        ScriptBundle.from_files({"main.py": b"", name: b"x"})


def test_bad_bundles_name_the_problem(tmp_path):
    with pytest.raises(ValueError, match="not among"):
        ScriptBundle.from_files({"other.py": b""})
    with pytest.raises(ValueError, match="Python file"):
        ScriptBundle.from_files({"data.txt": b""}, entry="data.txt")
    with pytest.raises(ValueError, match="limit"):
        ScriptBundle.from_files({"main.py": b"", "big.bin": b"\0" * (MAX_BYTES + 1)})
    with pytest.raises(ValueError, match="both a file and a folder"):
        ScriptBundle.from_files({"main.py": b"", "lib": b"", "lib/x.py": b""})
    root = tmp_path / "d"
    root.mkdir()
    with pytest.raises(ValueError, match="main.py"):
        ScriptBundle.from_path(root)  # no entry file
    (root / "main.py").write_text("")
    os.symlink("/etc/hostname", root / "link.txt")
    with pytest.raises(ValueError, match="symlink"):
        ScriptBundle.from_path(root)
    with pytest.raises(ValueError, match="only for a directory"):
        ScriptBundle.from_path(root / "main.py", entry="main.py")


def test_hidden_files_and_caches_are_left_out(tmp_path):
    root = tmp_path / "d"
    (root / "__pycache__").mkdir(parents=True)
    (root / ".git").mkdir()
    (root / "main.py").write_text("")
    (root / ".env").write_text("TOKEN=1")
    (root / ".git" / "config").write_text("")
    (root / "__pycache__" / "main.cpython-311.pyc").write_bytes(b"\0")
    assert [name for name, _ in ScriptBundle.from_path(root).files] == ["main.py"]


@confined
def test_cli_runs_and_verifies_a_directory(tmp_path, capsys):
    from swarmdeck.console.cli import main

    root = experiment_dir(tmp_path)
    assert main(["run", "--sandbox", str(root), "--robots", "2", "--duration", "0.3"]) == 0
    assert "PARAM spacing=0.3" in capsys.readouterr().out
    assert main(["run", str(root), "--entry", "main.py"]) == 2  # --entry without --sandbox: usage error
    assert "--entry needs --sandbox" in capsys.readouterr().err
    assert main(["verify", str(root), "--entry", "nothere.py", "--runs", "1", "--duration", "0.3"]) == 2
    assert "nothere.py" in capsys.readouterr().err
