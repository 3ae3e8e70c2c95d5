"""CI runs hypothesis deterministically: with ``CI`` set the ``ci`` profile
(derandomized, no example database, no deadline) is the default of every test."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_ci_sets_a_derandomized_profile_without_database(tmp_path):
    probe = tmp_path / "test_probe.py"
    probe.write_text(textwrap.dedent("""
        from hypothesis import given, settings, strategies as st

        SEEN = []

        def test_default_profile():
            s = settings.default
            assert s.derandomize is True and s.database is None and s.deadline is None, s

        @settings(max_examples=15)
        @given(st.integers())
        def test_examples(x):
            SEEN.append(x)

        def test_report():
            print("EXAMPLES", SEEN)
    """))
    conftest = tmp_path / "conftest.py"
    conftest.write_text((ROOT / "tests" / "conftest.py").read_text())
    env = {k: v for k, v in os.environ.items() if not k.startswith("HYPOTHESIS")}
    env["CI"] = "true"
    env["PYTHONPATH"] = str(ROOT / "tests")  # the conftest registers the shared fixture modules (pytest_plugins)
    env["PYTEST_DISABLE_PLUGIN_AUTOLOAD"] = "1"  # hypothesis registers its plugin on import
    outs = []
    for _ in range(2):
        r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-s", "-p", "no:cacheprovider",
                            str(probe)], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
        assert r.returncode == 0, r.stdout + r.stderr
        outs.append([ln[ln.index("EXAMPLES"):] for ln in r.stdout.splitlines() if "EXAMPLES" in ln])
    assert outs[0] == outs[1] and outs[0]  # the same examples on every run
    assert not (tmp_path / ".hypothesis" / "examples").exists()  # no example database written


def test_profile_choice_follows_the_environment():
    sys.path.insert(0, str(ROOT / "tests"))
    try:
        from conftest import hypothesis_profile
    finally:
        sys.path.pop(0)
    assert hypothesis_profile({}) == "dev"
    assert hypothesis_profile({"CI": "true"}) == "ci"
    assert hypothesis_profile({"CI": "0"}) == "dev"
    assert hypothesis_profile({"CI": "1", "HYPOTHESIS_PROFILE": "dev"}) == "dev"
