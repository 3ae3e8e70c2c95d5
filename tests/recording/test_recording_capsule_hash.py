"""The capsule's hashes: run_key (the sweeps' cache key) depends on the bytes and values only, never on their order;
every byte counts; unsafe names and non-JSON values are refused by name; manifests round-trip with their hash."""
from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.console.recording.capsule import (
    Manifest,
    capsule_hash,
    check_relative_path,
    environment,
    environment_differences,
    is_newer,
    manifest_for,
    run_key,
    sha256_hex,
)

names = st.sampled_from(["main.py", "s.py", "lib/util.py", "lib/deep/x.py", "data/params.toml", "a b.py"])
files = st.dictionaries(names, st.binary(max_size=64), min_size=1, max_size=4)
values = st.dictionaries(st.text(max_size=6), st.one_of(st.integers(), st.booleans(), st.text(max_size=8),
                                                        st.floats(allow_nan=False, allow_infinity=False)), max_size=4)


@settings(max_examples=30)
@given(files=files, params=values, seed=st.none() | st.integers(0, 2**63), config=values)
def test_run_key_ignores_order_and_sees_every_byte(files, params, seed, config) -> None:
    key = run_key(files, params=params, seed=seed, config=config)
    assert len(key) == 64
    assert run_key(dict(reversed(list(files.items()))), params=dict(reversed(list(params.items()))), seed=seed,
                   config=dict(reversed(list(config.items())))) == key
    name = sorted(files)[0]
    assert run_key({**files, name: files[name] + b"\0"}, params=params, seed=seed, config=config) != key
    assert run_key(files, params=params, seed=(seed or 0) + 1, config=config) != key
    assert run_key(files, params={**params, "__extra": 1}, seed=seed, config=config) != key


def test_known_key_and_hash_values() -> None:
    """Pinned: a change to the hashing would silently invalidate every cached sweep."""
    assert sha256_hex(b"") == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
    key = run_key({"s.py": b"print(1)\n"}, params={"gain": 0.5}, seed=3, config={"robots": 10})
    assert key == "d27c5208a3f25368ffeeefd563a22c00f9120917213266cf29bdb9895fb9ac69"


@pytest.mark.parametrize("bad", ["../x.py", "/abs.py", "a//b.py", "a/./b.py", "a\\b.py", "C:x.py", "", "a/../b"])
def test_unsafe_names_are_refused(bad) -> None:
    with pytest.raises(ValueError, match="file name"):
        check_relative_path(bad)
    with pytest.raises(ValueError):
        run_key({bad: b""})


def test_non_json_and_nan_values_are_refused() -> None:
    with pytest.raises(ValueError, match="not canonical JSON"):
        run_key({"s.py": b""}, params={"gain": float("nan")})
    with pytest.raises(ValueError, match="not canonical JSON"):
        run_key({"s.py": b""}, config={"when": object()})
    with pytest.raises(ValueError, match="seed"):
        run_key({"s.py": b""}, seed=True)


def test_a_manifest_round_trips_with_its_hash_and_names_bad_fields() -> None:
    m = manifest_for("run", {"s.py": b"x = 1\n"}, entry="s.py", run={"seed": 4, "robots": 3})
    d = m.to_dict()
    assert d["hash"] == capsule_hash(d) and Manifest.from_dict(d) == m
    assert m.key == run_key({"s.py": b"x = 1\n"}, entry="s.py", seed=4, config={"robots": 3})
    with pytest.raises(ValueError, match="kind"):
        Manifest.from_dict({**d, "kind": "party"})
    with pytest.raises(ValueError, match="'files' missing"):
        Manifest.from_dict({k: v for k, v in d.items() if k != "files"})
    with pytest.raises(ValueError, match="entry"):
        Manifest.from_dict({**d, "entry": "other.py"})
    with pytest.raises(ValueError, match="SHA-256"):
        Manifest.from_dict({**d, "files": {"s.py": "abc"}})


def test_versions_and_environment_differences() -> None:
    assert is_newer("0.2", "0.1.9") and not is_newer("0.1.0", "0.1") and is_newer("1.0rc1", "0.9")
    env = environment()
    assert environment_differences(env, env) == []
    other = {**env, "python": "2.7.18", "packages": {**env["packages"], "numpy": "0.1", "newpkg": "1"}}
    diffs = environment_differences(other, env)
    assert f"python: recorded 2.7.18, here {env['python']}" in diffs
    assert any(d.startswith("package numpy: recorded 0.1") for d in diffs)
    assert "package newpkg: recorded 1, here not installed" in diffs


def test_a_script_folder_is_taken_whole_but_links_and_caches(tmp_path) -> None:
    from swarmdeck.console.recording.capsule_zip import CapsuleError, script_files

    (tmp_path / "lib").mkdir()
    (tmp_path / "__pycache__").mkdir()
    (tmp_path / "main.py").write_text("import lib.u\n")
    (tmp_path / "lib" / "u.py").write_text("X = 1\n")
    (tmp_path / ".params.toml").write_text("gain = 2\n")
    (tmp_path / "__pycache__" / "main.cpython-311.pyc").write_bytes(b"\0")
    (tmp_path / "passwd").symlink_to("/etc/passwd")
    files, entry = script_files(tmp_path)
    assert entry == "main.py" and sorted(files) == [".params.toml", "lib/u.py", "main.py"]
    assert script_files(tmp_path / "lib" / "u.py") == ({"u.py": b"X = 1\n"}, "u.py")
    with pytest.raises(CapsuleError, match="no entry file 'run.py'"):
        script_files(tmp_path, "run.py")
