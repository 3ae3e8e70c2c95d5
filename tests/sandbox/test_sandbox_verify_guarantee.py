"""The verification report states a bound on P(contact per run) from its raw runs, `--epsilon/--confidence`
pick the run count, and a bound above ε refuses the bypass with the reason (REFERENCE.md §17)."""
import json
import textwrap
from pathlib import Path

import jsonschema
import pytest

import swarmdeck.console.sandbox as jobs
from swarmdeck.console.cli import main
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor
from swarmdeck.console.sandbox.report_html import render_html
from swarmdeck.console.sandbox.verification import ACCEPTED, BYPASS, VerificationConfig, verify

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
SCHEMA = json.loads((Path(jobs.__file__).parent / "verification_report.schema.json").read_text())
SPIN = """
import numpy as np
def experiment(arena):
    while True:  # every robot turns on the spot: nobody moves towards anybody
        arena.set_unicycle(np.zeros(arena.n), np.full(arena.n, 1.0))
        arena.step()
"""
RENDEZVOUS = """
def experiment(arena):
    while True:
        p = arena.positions()
        arena.set_velocities(-3.0 * (p - p.mean(axis=0)))
        arena.step()
"""


def verify_source(tmp_path, source, **config):
    path = tmp_path / "script.py"
    path.write_text(textwrap.dedent(source))
    settings = dict(n_robots=4, duration=2.0, runs=2, seed=5)
    settings.update(config)
    return verify([path], VerificationConfig(**settings), SerialExecutor())


def test_a_clean_script_states_the_rule_of_three_bound_and_bypasses_without_epsilon(tmp_path):
    report = verify_source(tmp_path, SPIN)
    script = report.scripts[0]
    assert report.verdict == BYPASS
    assert script["contact_bound"]["statement"] == "P(contact per run) ≤ 77.7 % at 95 % confidence (2 runs, 0 contacts)"
    assert script["contact_bound"]["met"] is None
    data = report.to_dict()
    jsonschema.validate(data, SCHEMA)
    assert "P(contact per run) ≤ 77.7 % at 95 % confidence (2 runs, 0 contacts)" in render_html(data)


def test_a_bound_above_epsilon_refuses_the_bypass_with_the_reason(tmp_path):
    report = verify_source(tmp_path, SPIN, epsilon=0.01)
    script = report.scripts[0]
    assert report.verdict == ACCEPTED  # S = 1 and no contact: the mean score alone would have let it bypass
    assert report.safety_score == 1.0
    assert script["bypass_refused_because"] == [
        "P(contact per run) ≤ 77.7 % at 95 % confidence (2 runs, 0 contacts): above the required 1.0 %; "
        "299 runs with 0 contacts would reach it"]
    assert script["contact_bound"]["met"] is False and script["contact_bound"]["runs_needed"] == 299
    jsonschema.validate(report.to_dict(), SCHEMA)
    assert "not met (299 runs would be needed)" in render_html(report.to_dict())


def test_a_bound_within_epsilon_allows_the_bypass(tmp_path):
    report = verify_source(tmp_path, SPIN, epsilon=0.8)
    assert report.verdict == BYPASS and report.scripts[0]["contact_bound"]["met"] is True


def test_raw_runs_with_contacts_are_counted_by_clopper_pearson(tmp_path):
    report = verify_source(tmp_path, RENDEZVOUS, n_robots=8, duration=6.0, seed=3, epsilon=0.5)  # both raw runs touch
    bound = report.scripts[0]["contact_bound"]
    assert report.verdict == ACCEPTED
    assert bound["contacts"] == 2 and bound["bound"] == 1.0 and bound["method"] == "Clopper-Pearson"
    assert bound["statement"] == "P(contact per run) ≤ 100.0 % at 95 % confidence (2 runs, 2 contacts)"


def cli(tmp_path, *extra):
    script = tmp_path / "spin.py"
    script.write_text(textwrap.dedent(SPIN))
    return ["verify", str(script), "--robots", "2", "--duration", "0.5", "--workers", "1", *extra]


def test_epsilon_and_confidence_pick_the_run_count(tmp_path, capsys):
    assert main(cli(tmp_path, "--epsilon", "0.5", "--confidence", "0.75", "--json")) == 0
    out = capsys.readouterr()
    report = json.loads(out.out)
    jsonschema.validate(report, SCHEMA)
    assert report["config"]["runs"] == 2  # (1 − 0.5)^2 = 0.25 ≤ 1 − 0.75 and (1 − 0.5)^1 > 0.25
    assert report["config"]["epsilon"] == 0.5 and report["config"]["confidence"] == 0.75
    assert "2 runs per script: the fewest with (1 - 0.5)^n <= 1 - 0.75" in out.err
    assert report["verdict"] == "accepted, may bypass the barrier"
    assert report["scripts"][0]["contact_bound"]["statement"] == \
        "P(contact per run) ≤ 50.0 % at 75 % confidence (2 runs, 0 contacts)"


def test_the_text_output_states_the_bound_and_too_few_runs_are_named(tmp_path, capsys):
    assert main(cli(tmp_path, "--runs", "1", "--epsilon", "0.5")) == 0
    out = capsys.readouterr()
    assert "note: 1 runs cannot bound P(contact per run) by 0.5 at 0.95 confidence (that needs 5 runs" in out.err
    assert "P(contact per run) ≤ 95.0 % at 95 % confidence (1 run, 0 contacts)" in out.out
    assert "no bypass: P(contact per run) ≤ 95.0 % at 95 % confidence (1 run, 0 contacts): above the required 50.0 %" \
        in out.out


@pytest.mark.parametrize("extra,message", [
    (("--confidence", "1.5"), "confidence must be a number strictly between 0 and 1"),
    (("--confidence", "0"), "confidence must be"),
    (("--epsilon", "0"), "epsilon (the target P(contact per run)) must be a number strictly between 0 and 1"),
    (("--epsilon", "-0.1"), "epsilon"),
    (("--epsilon", "1e-12"), "more than 10000000"),
])
def test_bad_epsilon_or_confidence_exits_2_naming_it(tmp_path, capsys, extra, message):
    assert main(cli(tmp_path, *extra)) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and message in err and "--epsilon/--confidence" in err
