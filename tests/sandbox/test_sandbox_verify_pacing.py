"""Verification varies tick pacing (issue 24, item 2): the first raw runs tick in real time like the arena (33 ms
per tick), so a script cannot tell verification apart by timing alone — one that behaves only while ticks come
fast loses the bypass — and pacing never changes what is simulated: the verdict of a script that behaves the same
either way is the same, bit for bit."""
import json
import textwrap

import numpy as np
import pytest

from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor
from swarmdeck.console.sandbox.verification import ACCEPTED, VerificationConfig, verify

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

FACING = ((-0.3, 0.0, 0.0), (0.3, 0.0, np.pi))
TWO_FACED = """
import time
import numpy as np
def experiment(arena):
    stamps = []
    for _ in range(9):  # hold still and time the ticks
        arena.set_unicycle(np.zeros(arena.n), np.zeros(arena.n))
        arena.step()
        stamps.append(time.monotonic())
    paced = np.median(np.diff(stamps)) >= 0.03  # real-time ticks: this must be the arena
    while True:
        arena.set_unicycle(np.full(arena.n, 0.2 if paced else 0.0), np.zeros(arena.n))
        arena.step()
"""
ROTATE = """
import numpy as np
def experiment(arena):
    while True:
        arena.set_unicycle(np.full(arena.n, 0.05), np.full(arena.n, 0.8))
        arena.step()
"""


def verify_source(tmp_path, source, **config):
    script = tmp_path / "script.py"
    script.write_text(textwrap.dedent(source))
    settings = dict(n_robots=2, duration=3.0, runs=2, seed=2, initial_poses=FACING)
    settings.update(config)
    return verify([script], VerificationConfig(**settings), SerialExecutor())


def test_a_script_that_attacks_when_ticks_come_in_real_time_loses_the_bypass(tmp_path):
    report = verify_source(tmp_path, TWO_FACED)
    runs = report.scripts[0]["runs"]
    paced = [r for r in runs if r["paced"]]
    assert [(r["index"], r["mode"]) for r in paced] == [(0, "raw")]
    assert paced[0]["contacts"]["count"] > 0 and paced[0]["safety_score"] < 1.0  # it drove head-on
    assert report.verdict == ACCEPTED  # never "may bypass"
    assert report.to_dict()["config"]["paced_runs"] == 1


def test_pacing_changes_nothing_that_is_simulated(tmp_path):
    paced = verify_source(tmp_path, ROTATE, duration=1.0, paced_runs=2).to_dict()
    fast = verify_source(tmp_path, ROTATE, duration=1.0, paced_runs=0).to_dict()
    assert [r["paced"] for r in paced["scripts"][0]["runs"]] == [True, False, True, False]
    for report in (paced, fast):
        del report["config"]["paced_runs"]
        for r in report["scripts"][0]["runs"]:
            del r["paced"]
    assert json.dumps(paced, sort_keys=True) == json.dumps(fast, sort_keys=True)
