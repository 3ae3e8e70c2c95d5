"""Verification cannot be stalled or inflated (issue 24, item 4): a stale, late or missing answer is a missed tick
(robots stopped, simulated time goes on, counted), every run ends within a wall-time budget derived from the
declared duration, and a script cannot make the trusted side simulate more robots than declared."""
import textwrap

import pytest
from hostile_scripts import FIVE_HUNDRED, STALE_FOREVER

from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor
from swarmdeck.console.sandbox.verification import REJECTED, VerificationConfig, verify

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

STALE_EVERY_OTHER = """
def experiment(arena):
    k = 0
    while True:
        k += 1
        if k % 2:
            arena.backend._k -= 1  # every other answer is stale
        arena.step()
"""
SLEEPY = """
import time
def experiment(arena):
    while True:
        time.sleep(0.9)  # within the 1 s per-tick budget, but 27 wall s per simulated s
        arena.step()
"""


def runs_of(tmp_path, source, **config):
    script = tmp_path / "script.py"
    script.write_text(textwrap.dedent(source))
    settings = dict(n_robots=1, duration=2.0, runs=1, paced_runs=0)
    settings.update(config)
    report = verify([script], VerificationConfig(**settings), SerialExecutor())
    return report, report.scripts[0]["runs"]


def test_stale_tick_numbers_forever_are_missed_ticks_that_end_the_run(tmp_path):
    report, runs = runs_of(tmp_path, STALE_FOREVER)
    assert report.verdict == REJECTED
    for r in runs:  # each stale answer stopped the robots for one tick and simulated time went on
        assert r["ended_by"] == "overruns" and r["ticks"] == r["overruns"] == 5, r
        assert r["time"] == pytest.approx(5 * 0.033)
        assert "an answer for another tick" in r["error"]


def test_stale_answers_between_good_ones_cannot_hold_simulated_time(tmp_path):
    report, runs = runs_of(tmp_path, STALE_EVERY_OTHER, duration=1.0)
    for r in runs:  # the run reaches its declared duration, half its ticks missed
        assert r["ended_by"] == "duration" and r["time"] >= 1.0 - 1e-9, r
        assert r["overruns"] >= r["ticks"] // 2 - 1 and r["ticks"] == 31


def test_a_script_sleeping_through_every_tick_ends_at_the_wall_budget(tmp_path):
    report, runs = runs_of(tmp_path, SLEEPY, wall_factor=1.5, boot_s=4.0)
    budget = report.to_dict()["config"]["wall_budget"]
    assert budget == {"factor": 1.5, "boot_s": 4.0, "run_s": 7.0, "job_s": 14.0}  # 2 runs × (4 s + 1.5 × 2 s)
    assert report.to_dict()["config"]["limits"]["wall_s"] == 7.0
    assert report.verdict == REJECTED
    for r in runs:
        assert r["ended_by"] == "wall" and r["time"] < 2.0, r
        assert "used up its verification budget of 7 s wall time (4 s start-up + 1.5 × the declared 2 s)" in r["error"]


def test_an_arena_of_500_when_1_was_declared_is_refused_before_anything_is_simulated(tmp_path):
    report, runs = runs_of(tmp_path, FIVE_HUNDRED)
    assert report.verdict == REJECTED
    for r in runs:
        assert r["ended_by"] == "arena" and r["n_robots"] == 500 and r["ticks"] == 0 and r["time"] == 0.0, r
        assert "the script asks for 500 robots but the manifest declares 1" in r["error"]
        assert r["start_poses"] is None  # no plant was built
