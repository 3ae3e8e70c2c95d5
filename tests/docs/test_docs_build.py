"""The documentation site builds with warnings as errors (``mkdocs build --strict``, as CI and a writer would
run it): every page in the nav, every link and anchor resolves, and the API reference is generated from the
docstrings."""
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_the_docs_build_strict(tmp_path):
    site = tmp_path / "site"
    out = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(site)], cwd=ROOT,
                         capture_output=True, text=True, timeout=600, env={**__import__("os").environ,
                                                                          "NO_MKDOCS_2_WARNING": "1"})
    assert out.returncode == 0, out.stderr[-5000:]
    for page in ("index.html", "script-environment/index.html", "tutorials/first-experiment/index.html",
                 "tutorials/running-a-lab/index.html", "security/index.html", "architecture/index.html"):
        assert (site / page).is_file(), page
    api = (site / "api" / "experiments" / "index.html").read_text()
    assert "set_velocities" in api and "A swarm of GRITSBots you program at the level you like" in api
    touch = (site / "tutorials" / "touch-input" / "index.html").read_text()
    assert "oscsend" in touch  # inputs/README.md is included
