"""Verdicts of `verify` on fixture scripts, and every bad input of issue 15 as a clear `rejected` reason."""
import textwrap

import pytest

from swarmdeck.console.sandbox.confinement import SandboxLimits, probe
from swarmdeck.console.sandbox.executors import SerialExecutor
from swarmdeck.console.sandbox.verification import ACCEPTED, BYPASS, REJECTED, VerificationConfig, verify

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

RENDEZVOUS = """
def experiment(arena):
    while True:
        p = arena.positions()
        arena.set_velocities(-3.0 * (p - p.mean(axis=0)))
        arena.step()
"""
FORMATION = """
import numpy as np
def experiment(arena):
    while True:  # every robot turns on the spot: the formation holds, nobody moves towards anybody
        arena.set_unicycle(np.zeros(arena.n), np.full(arena.n, 1.0))
        arena.step()
"""


def verify_source(tmp_path, source, name="script.py", **config):
    path = tmp_path / name
    path.write_text(textwrap.dedent(source))
    settings = dict(n_robots=6, duration=6.0, runs=2, seed=3)
    settings.update(config)
    return verify([path], VerificationConfig(**settings), SerialExecutor())


def test_a_rendezvous_that_collides_without_the_barrier_is_accepted_with_it(tmp_path):
    report = verify_source(tmp_path, RENDEZVOUS, n_robots=8)
    script = report.scripts[0]
    assert report.verdict == ACCEPTED and script["reasons"] == []
    assert report.safety_score < 1.0
    raw = [r for r in script["runs"] if r["mode"] == "raw"]
    wrapped = [r for r in script["runs"] if r["mode"] == "wrapped"]
    assert all(r["contacts"]["count"] > 0 for r in raw)
    assert all(r["contacts"]["first_time"] is not None and r["contact_points"] for r in raw)
    assert all(r["contacts"]["count"] == 0 and r["min_distance"] > 0.11 for r in wrapped)
    assert any("contacts without the barrier" in why for why in script["bypass_refused_because"])


def test_a_formation_that_never_collides_may_bypass_the_barrier(tmp_path):
    report = verify_source(tmp_path, FORMATION)
    assert report.verdict == BYPASS and report.safety_score == 1.0
    assert all(r["contacts"]["count"] == 0 for r in report.scripts[0]["runs"])


@pytest.mark.parametrize("name,source,expected", [
    ("crash", "def experiment(arena):\n    arena.step()\n    raise RuntimeError('boom')\n",
     "crash.py:3 (in experiment): RuntimeError: boom"),
    ("syntax", "def experiment(arena)\n    pass\n", "syntax error in"),
    ("missing", "import no_such_module_here\n", "missing.py:1 (in <module>): ModuleNotFoundError: No module named 'no_such_module_here'"),
    ("nan", "import numpy as np\ndef experiment(arena):\n    while True:\n        arena.set_velocities(np.full((arena.n, 2), np.nan))\n        arena.step()\n",
     "non-finite (NaN/inf) robot commands"),
    ("garbage", "def experiment(arena):\n    arena.set_velocities('fast')\n",
     "garbage.py:2 (in experiment): ValueError: velocities must be numeric"),
    ("fewer", "import rps.robotarium as robotarium\nr = robotarium.Robotarium(number_of_robots=19)\nr.step()\n",
     "the script asks for 19 robots but the manifest declares 20"),
])
def test_bad_scripts_are_rejected_with_the_reason(tmp_path, name, source, expected):
    n = 20 if name == "fewer" else 3
    report = verify_source(tmp_path, source, name=f"{name}.py", n_robots=n, duration=0.5, runs=1)
    assert report.verdict == REJECTED
    assert any(expected in reason for reason in report.to_dict()["reasons"]), report.to_dict()["reasons"]


def test_an_endless_tick_is_rejected_and_does_not_touch_the_other_script(tmp_path):
    hang = tmp_path / "hang.py"
    hang.write_text("def experiment(arena):\n    arena.step()\n    while True:\n        pass\n")
    good = tmp_path / "good.py"
    good.write_text(textwrap.dedent(FORMATION))
    config = VerificationConfig(n_robots=3, duration=0.5, runs=1, limits=SandboxLimits(tick_s=0.3, max_overruns=2))
    report = verify([hang, good], config, SerialExecutor())
    verdicts = {s["script"]: s for s in report.scripts}
    assert verdicts["hang.py"]["verdict"] == REJECTED
    assert "per-tick compute budget" in verdicts["hang.py"]["reasons"][0]
    assert verdicts["good.py"]["verdict"] == BYPASS
    assert report.verdict == REJECTED


def test_archives_are_refused_before_anything_runs(tmp_path):
    bomb = tmp_path / "bomb.zip"
    bomb.write_bytes(b"PK\x03\x04" + b"\0" * 100)
    with pytest.raises(ValueError, match="archives are not accepted"):
        verify([bomb], VerificationConfig(runs=1), SerialExecutor())
