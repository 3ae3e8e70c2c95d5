"""A `swarmdeck run --record` recording carries its capsule; `swarmdeck capsule` writes run.zip; `swarmdeck run run.zip`
re-executes it bit for bit — and refuses, or says exactly where and why it differs, for capsules that were changed."""
from __future__ import annotations

import json
import zipfile
from pathlib import Path

import pytest

from swarmdeck.console.cli import main as cli
from swarmdeck.console.recording.capsule import capsule_hash, package_version
from swarmdeck.console.recording.capsule_zip import read_recorded_capsule

SCRIPT = """import numpy as np

def experiment(arena):
    goals = np.array([[0.5, 0.3], [-0.5, -0.3], [0.4, -0.4]])[: arena.n]
    while arena.time < arena.duration - 1e-9:
        arena.set_velocities(goals - arena.positions())
        arena.step()
"""


@pytest.fixture(scope="module")
def capsule(tmp_path_factory) -> Path:
    """A 3-robot, 0.5 s run with a seed and an obstacles file, recorded and made into run.zip."""
    d = tmp_path_factory.mktemp("capsule")
    (d / "goals.py").write_text(SCRIPT)
    (d / "walls.toml").write_text("[arena]\nobstacles = [[[0.9, -0.2], [0.9, 0.2]]]\n")
    assert cli(["run", str(d / "goals.py"), "--robots", "3", "--duration", "0.5", "--seed", "7", "--obstacles",
                str(d / "walls.toml"), "--record", str(d / "r.mcap"), "--no-foxglove-channels"]) == 0
    assert cli(["capsule", str(d / "r.mcap"), "-o", str(d / "run.zip")]) == 0
    return d / "run.zip"


def _rewrite(src: Path, dst: Path, *, manifest=None, members: dict[str, bytes] | None = None,
             rehash: bool = True) -> Path:
    """A copy of capsule ``src`` with ``manifest(dict) -> dict`` applied and ``members`` replaced (or added)."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for info in zin.infolist():
            data = zin.read(info.filename)
            if info.filename == "manifest.json" and manifest is not None:
                m = manifest(json.loads(data))
                if rehash:
                    m["hash"] = capsule_hash(m)
                data = json.dumps(m).encode()
            if members and info.filename in members:
                data = members.pop(info.filename)
            zout.writestr(info.filename, data)
        for name, data in (members or {}).items():
            zout.writestr(name, data)
    return dst


def test_the_recording_carries_its_script_arguments_and_environment(capsule) -> None:
    got = read_recorded_capsule(capsule.parent / "r.mcap")
    m = got.manifest
    assert m is not None and m.kind == "run" and m.entry == "goals.py"
    assert set(got.files) == {"goals.py", "_capsule/obstacles.toml"} and got.files["goals.py"] == SCRIPT.encode()
    assert m.run["seed"] == 7 and m.run["robots"] == 3 and m.run["duration"] == 0.5 and m.run["safety"] is True
    assert m.environment["swarmdeck"] == package_version("swarmdeck")
    assert m.environment["packages"]["numpy"] == package_version("numpy")
    with zipfile.ZipFile(capsule) as z:
        assert sorted(z.namelist()) == ["files/_capsule/obstacles.toml", "files/goals.py", "manifest.json",
                                        "recording.mcap"]


def test_a_capsule_reproduces_its_run_bit_for_bit(capsule, capsys) -> None:
    capsys.readouterr()
    assert cli(["run", str(capsule)]) == 0
    out = capsys.readouterr().out
    assert "bit-identical: all 16 frames reproduce the recording exactly" in out, out


def test_a_changed_script_with_matching_hashes_runs_and_names_the_first_difference(capsule, tmp_path, capsys) -> None:
    """A colleague's edit (the hashes updated with it): not identical, naming time, robot and quantity; exit 1."""
    changed = SCRIPT.replace("[-0.5, -0.3]", "[-0.5, -0.2]").encode()
    from swarmdeck.console.recording.capsule import sha256_hex

    def edit(m):
        m["files"]["goals.py"] = sha256_hex(changed)
        return m

    z = _rewrite(capsule, tmp_path / "edited.zip", manifest=edit, members={"files/goals.py": changed})
    capsys.readouterr()
    assert cli(["run", str(z), "--json"]) == 1
    v = json.loads(capsys.readouterr().out)
    assert not v["bit_identical"]
    first = v["first_difference"]
    assert first["robot"] == 1 and first["quantity"] == "nominal" and first["tick"] == 0 and first["time"] == 0.0


def test_different_packages_run_but_bit_identity_is_not_claimed(capsule, tmp_path, capsys) -> None:
    def older_numpy(m):
        m["environment"]["packages"]["numpy"] = "1.0.0"
        m["environment"]["platform"] = "Plan9-4"
        return m

    z = _rewrite(capsule, tmp_path / "numpy.zip", manifest=older_numpy)
    capsys.readouterr()
    assert cli(["run", str(z)]) == 3
    out = capsys.readouterr().out
    assert "all 16 frames are identical, but the environment differs, so bit-identity is not claimed" in out
    assert f"package numpy: recorded 1.0.0, here {package_version('numpy')}" in out
    assert "platform: recorded Plan9-4" in out


def test_a_tampered_capsule_is_refused_naming_each_file(capsule, tmp_path, capsys) -> None:
    z = _rewrite(capsule, tmp_path / "t.zip", members={"files/goals.py": SCRIPT.encode() + b"\nimport os\n",
                                                       "files/_capsule/obstacles.toml": b"[arena]\n"})
    assert cli(["run", str(z)]) == 2
    err = capsys.readouterr().err
    assert "tampered" in err and "files/goals.py: SHA-256" in err and "files/_capsule/obstacles.toml: SHA-256" in err


def test_a_capsule_from_a_newer_swarmdeck_is_refused_naming_both_versions(capsule, tmp_path, capsys) -> None:
    def newer(m):
        m["environment"]["swarmdeck"] = "99.1"
        return m

    assert cli(["run", str(_rewrite(capsule, tmp_path / "n.zip", manifest=newer))]) == 2
    err = capsys.readouterr().err
    assert f"written by swarmdeck 99.1, newer than this swarmdeck {package_version('swarmdeck')}" in err


@pytest.mark.parametrize("name", ["../evil.py", "/etc/evil.py", "files/../../evil.py", "files\\..\\evil.py"])
def test_path_traversal_is_refused_and_nothing_is_written_outside(capsule, tmp_path, capsys, name) -> None:
    work = tmp_path / "w"
    work.mkdir()
    z = _rewrite(capsule, work / "trav.zip", members={name: b"print('pwned')\n"})
    assert cli(["run", str(z)]) == 2
    assert "path traversal refused" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.rglob("evil.py")) == []
    assert not Path("/etc/evil.py").exists()


def test_not_a_zip_and_no_manifest_are_refused(tmp_path, capsule, capsys) -> None:
    bad = tmp_path / "bad.zip"
    bad.write_bytes(b"PK not really")
    assert cli(["run", str(bad)]) == 2
    assert "not a zip file" in capsys.readouterr().err
    with zipfile.ZipFile(capsule) as zin, zipfile.ZipFile(tmp_path / "nom.zip", "w") as zout:
        zout.writestr("recording.mcap", zin.read("recording.mcap"))
    assert cli(["run", str(tmp_path / "nom.zip")]) == 2
    assert "no manifest.json in the zip" in capsys.readouterr().err


def test_a_recording_without_a_capsule_is_refused_by_swarmdeck_capsule(tmp_path, capsys) -> None:
    before = Path(__file__).resolve().parents[1] / "data" / "console_before_operator_events.mcap"
    assert cli(["capsule", str(before), "-o", str(tmp_path / "x.zip")]) == 2
    assert "carries no capsule" in capsys.readouterr().err
    assert not (tmp_path / "x.zip").exists()


def test_options_that_would_change_the_run_are_refused_with_a_capsule(capsule, capsys) -> None:
    assert cli(["run", str(capsule), "--robots", "5", "--no-safety"]) == 2
    assert "a capsule runs with the arguments it recorded: drop --robots --no-safety" in capsys.readouterr().err


def test_a_newer_capsule_format_is_refused_naming_both_formats(capsule, tmp_path, capsys) -> None:
    def newer(m):
        m["format"] = 7
        return m

    assert cli(["run", str(_rewrite(capsule, tmp_path / "f.zip", manifest=newer))]) == 2
    assert "is in capsule format 7, written by a newer swarmdeck; this swarmdeck reads format 1" in capsys.readouterr().err


def test_swarmdeck_info_names_the_capsule(capsule, capsys) -> None:
    capsys.readouterr()
    assert cli(["info", str(capsule.parent / "r.mcap")]) == 0
    assert "capsule     run: 2 script file(s), key " in capsys.readouterr().out


def test_an_unseeded_recorded_run_draws_and_records_its_seed(tmp_path, capsys) -> None:
    """Random start poses without --seed: the seed is drawn, said and recorded, so the capsule reproduces them."""
    (tmp_path / "goals.py").write_text(SCRIPT)
    assert cli(["run", str(tmp_path / "goals.py"), "--robots", "2", "--duration", "0.1", "--record",
                str(tmp_path / "u.mcap"), "--no-foxglove-channels"]) == 0
    seed = read_recorded_capsule(tmp_path / "u.mcap").manifest.run["seed"]
    assert isinstance(seed, int) and f"--seed {seed} (drawn for the recording" in capsys.readouterr().err
    assert cli(["capsule", str(tmp_path / "u.mcap"), "-o", str(tmp_path / "u.zip")]) == 0
    assert cli(["run", str(tmp_path / "u.zip")]) == 0
