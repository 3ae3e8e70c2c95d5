"""The falsification stage of `swarmdeck verify` end to end, jailed (issue 31 item 3): on the near-miss fixture
(examples/near_miss.py) the search finds the contact the random runs missed, reports it beside the bound without
changing the bound, refuses the bypass saying where and when, and keeps a recording of the worst case that replays
(`swarmdeck play` reads it with the same reader)."""
import json
from pathlib import Path

import jsonschema
import numpy as np
import pytest

import swarmdeck.console.sandbox as jobs
from swarmdeck.console.cli import main
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import LocalPoolExecutor
from swarmdeck.console.sandbox.report_html import render_html
from swarmdeck.console.sandbox.verification import ACCEPTED, VerificationConfig, load_script, script_verdict, verify
from swarmdeck.core.constants import ROBOT_DIAMETER

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
SCHEMA = json.loads((Path(jobs.__file__).parent / "verification_report.schema.json").read_text())
NEAR_MISS = Path(__file__).parents[2] / "examples" / "near_miss.py"
# seed 4: the search's first generation has the contact (its 4th run); one generation of 10 runs is spent
CONFIG = VerificationConfig(n_robots=2, duration=2.2, runs=1, seed=4, paced_runs=0, falsify_budget=20)


@pytest.fixture(scope="module")
def verified(tmp_path_factory):
    folder = tmp_path_factory.mktemp("worst")
    # a local pool of one worker, kept for the runs and every generation (LocalPoolExecutor.kept)
    return verify([NEAR_MISS], CONFIG, LocalPoolExecutor(1), worst_case_dir=folder), folder


def test_the_falsifier_finds_the_contact_and_refuses_the_bypass_saying_where(verified):
    report, _ = verified
    script = report.scripts[0]
    found = script["falsification"]
    assert [r["contacts"]["count"] for r in script["runs"]] == [0, 0]  # the random raw and wrapped runs: clean
    assert found["found_contact"] and found["runs"] == 10 and found["worst_case"]["run"] == 3
    assert found["worst_case"]["closest"]["robots"] == [0, 1]
    assert found["statement"] == "worst case found: a contact, replay attached (robots 0 and 1 at t = 1.6 s)"
    assert report.verdict == ACCEPTED
    assert script["bypass_refused_because"] == [
        "the falsifier found a contact without the barrier within the set-up tolerance: robots 0 and 1 at t = 1.6 s "
        "(searched run 3 of 10; replay near_miss-worst-case.mcap)"]
    setup = np.array(found["worst_case"]["probe"]["setup"])
    assert np.all(np.hypot(setup[:, 0], setup[:, 1]) <= 0.02 + 1e-9) and np.all(np.abs(setup[:, 2]) <= np.radians(5) + 1e-9)
    data = report.to_dict()
    jsonschema.validate(data, SCHEMA)
    assert data["config"]["falsify_budget"] == 20
    assert "worst case found: a contact, replay attached" in render_html(data)


def test_the_searched_runs_do_not_change_the_bound(verified):
    report, _ = verified
    script = report.scripts[0]
    without = script_verdict(load_script(NEAR_MISS), script["runs"], CONFIG)
    assert script["contact_bound"] == without["contact_bound"]
    assert script["contact_bound"]["runs"] == 1 and script["contact_bound"]["contacts"] == 0
    assert "falsification" not in without


def test_the_worst_case_recording_replays_the_contact(verified):
    report, folder = verified
    found = report.scripts[0]["falsification"]
    assert found["replay_matches"] is True
    with open_recording(folder / found["recording"]) as recording:
        frames = [frame for _, frame in recording.frames()]
    gaps = [float(np.linalg.norm(f.poses[0, :2] - f.poses[1, :2])) for f in frames]
    assert len(frames) == 67  # one frame per step (⌈2.2 s / 33 ms⌉)
    # the Frames hold the tracked poses (noise and the probe's offset, a few mm): a touch, where the nominal run
    # passes 75 mm clear
    assert min(gaps) == pytest.approx(ROBOT_DIAMETER, abs=0.012)
    start = np.array(found["worst_case"]["start_poses"])
    assert np.allclose(frames[0].poses[:, :2], start[:, :2], atol=0.015)  # the worst case's start, as tracked


def test_a_negative_budget_is_a_usage_error(capsys):
    assert main(["verify", str(NEAR_MISS), "--falsify-budget", "-1", "--trusted"]) == 2
    assert "--falsify-budget must be >= 0, got -1" in capsys.readouterr().err
