"""`swarmdeck verify`: exit status 0/1/2, the JSON report against its schema, the HTML report, refusals."""
import json
from pathlib import Path

import jsonschema
import pytest

import swarmdeck.console.sandbox as jobs
from swarmdeck.console.cli import main
from swarmdeck.console.sandbox import confinement
from swarmdeck.console.sandbox.confinement import ConfinementUnavailable, probe

SCHEMA = json.loads((Path(jobs.__file__).parent / "verification_report.schema.json").read_text())
SPIN = "import numpy as np\ndef experiment(arena):\n    while True:\n        arena.set_unicycle(np.zeros(arena.n), np.ones(arena.n))\n        arena.step()\n"
CRASH = "def experiment(arena):\n    arena.step()\n    raise KeyError('oops')\n"
confined = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")


def args(*scripts, extra=()):
    return ["verify", *map(str, scripts), "--robots", "2", "--duration", "0.5", "--runs", "1", "--workers", "1", *extra]


@confined
def test_accepted_exits_0_with_a_schema_valid_json_report_and_an_html_report(tmp_path, capsys):
    script = tmp_path / "spin.py"
    script.write_text(SPIN)
    html = tmp_path / "report.html"
    assert main(args(script, extra=("--json", "--html", str(html)))) == 0
    report = json.loads(capsys.readouterr().out)
    jsonschema.validate(report, SCHEMA)
    assert report["verdict"] == "accepted, may bypass the barrier" and report["safety_score"] == 1.0
    page = html.read_text()
    assert page.startswith("<!DOCTYPE html>") and "<svg" in page and "accepted, may bypass the barrier" in page
    assert "<script" not in page and "http" not in page.replace("http://www.w3.org", "")  # self-contained


@confined
def test_rejected_exits_1_and_names_the_scripts_line(tmp_path, capsys):
    script = tmp_path / "crash.py"
    script.write_text(CRASH)
    assert main(args(script)) == 1
    out = capsys.readouterr().out
    assert "crash.py: rejected" in out and "crash.py:3 (in experiment): KeyError: 'oops'" in out
    assert "safety score" not in out  # a rejected script shows no S (it said "S = 1.0000" of runs that failed)


@pytest.mark.parametrize("extra,message", [
    (("--runs", "0"), "--runs must be >= 1"),
    (("--duration", "-1"), "--duration must be"),
    (("--seed", "-3"), "--seed must be"),
    (("--workers", "0"), "--workers must be >= 1"),
    (("--bypass-threshold", "2"), "bypass_threshold must be in [0, 1]"),
])
def test_usage_errors_are_one_line_and_exit_2(tmp_path, capsys, extra, message):
    script = tmp_path / "spin.py"
    script.write_text(SPIN)
    assert main(args(script, extra=extra)) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and message in err


def test_a_missing_script_or_an_archive_exits_2(tmp_path, capsys):
    assert main(args(tmp_path / "nope.py")) == 2
    assert "does not exist" in capsys.readouterr().err
    archive = tmp_path / "bomb.zip"
    archive.write_bytes(b"PK\x05\x06" + b"\0" * 18)
    assert main(args(archive)) == 2
    assert "archives are not accepted" in capsys.readouterr().err


def test_without_confinement_untrusted_code_is_refused_unless_trusted(tmp_path, capsys, monkeypatch):
    script = tmp_path / "spin.py"
    script.write_text(SPIN)
    # a machine without bubblewrap and without namespaces
    monkeypatch.setattr(confinement.shutil, "which", lambda name: None)
    monkeypatch.setattr(confinement, "probe_unshare", lambda: "Linux namespaces are not available here: EPERM")
    confinement.probe_bwrap.cache_clear()
    try:
        assert probe() is not None and "bubblewrap" in probe() and "namespaces" in probe()
        assert main(args(script)) == 2
        err = capsys.readouterr().err
        assert "cannot confine untrusted code" in err and "--trusted" in err
        from swarmdeck.console.sandbox.executors import SerialExecutor
        from swarmdeck.console.sandbox.verification import VerificationConfig, verify

        with pytest.raises(ConfinementUnavailable):
            verify([script], VerificationConfig(n_robots=2, duration=0.5, runs=1), SerialExecutor())
        report = verify([script], VerificationConfig(n_robots=2, duration=0.5, runs=1, trusted=True), SerialExecutor())
        assert report.verdict == "accepted, may bypass the barrier" and report.to_dict()["config"]["trusted"] is True
    finally:
        confinement.probe_bwrap.cache_clear()

FORWARD = ("import numpy as np\ndef experiment(arena):\n    while True:\n"
           "        arena.set_unicycle(np.full(arena.n, 0.08), np.zeros(arena.n))\n        arena.step()\n")


@confined
def test_verify_what_you_will_submit_from_its_manifest_or_a_poses_file(tmp_path, capsys):
    script = tmp_path / "forward.py"
    script.write_text(FORWARD)
    manifest = tmp_path / "manifest.json"
    manifest.write_text(json.dumps({"name": "head-on", "robots": 2, "duration": 1.0, "no_barrier": True,
                                    "initial_poses": [[-0.115, 0, 0], [0.115, 0, 3.14159]]}))
    assert main(["verify", str(script), "--manifest", str(manifest), "--runs", "1", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    jsonschema.validate(report, SCHEMA)
    assert report["verdict"] == "accepted" and report["config"]["n_robots"] == 2 and report["config"]["duration"] == 1.0
    assert all(r["start_poses_from"] == "manifest" for r in report["scripts"][0]["runs"])
    poses = tmp_path / "poses.csv"
    poses.write_text("x,y,theta\n-0.5,0.5,0\n0.5,0.5,0\n0.0,-0.5,0\n")
    assert main(["verify", str(script), "--initial-poses", str(poses), "--duration", "0.5", "--runs", "1",
                 "--paced-runs", "0", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["config"]["n_robots"] == 3 and report["config"]["initial_poses"][2] == [0.0, -0.5, 0.0]
    assert all(r["start_poses_from"] == "manifest" and not r["paced"] for r in report["scripts"][0]["runs"])


@pytest.mark.parametrize("manifest,poses,message", [
    ({"name": "x", "robots": 2, "duration": 1, "initial_poses": [[0, 0, 0], [0.1, 0, 0]]}, None,
     "poses 0 (0.000, 0.000) and 1 (0.100, 0.000) are 0.100 m apart"),
    ({"name": "x", "robots": 2, "duration": 1, "colour": "red"}, None, "unknown manifest key 'colour'"),
    (None, "0,0,0\n3,0,0\n", "pose 1 (3.000, 0.000, 0.000) is outside the arena"),
    (None, "0,0\n", "expected 3 values x, y, theta"),
])
def test_bad_manifests_and_poses_files_exit_2_naming_what_is_wrong(tmp_path, capsys, manifest, poses, message):
    script = tmp_path / "forward.py"
    script.write_text(FORWARD)
    extra = []
    if manifest is not None:
        (tmp_path / "m.json").write_text(json.dumps(manifest))
        extra += ["--manifest", str(tmp_path / "m.json")]
    if poses is not None:
        (tmp_path / "p.csv").write_text(poses)
        extra += ["--initial-poses", str(tmp_path / "p.csv"), "--robots", "2"]
    assert main(["verify", str(script), "--runs", "1", *extra]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and message in err, err
