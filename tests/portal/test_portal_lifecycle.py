"""The whole life cycle through the commands a lab and a researcher type: `swarmdeck users add`, `swarmdeck server`
(real uvicorn, its own process, simulated arena --fast), `swarmdeck submit --wait`, `jobs`, `results` — the MCAP
opens with swarmdeck's reader, the CSV and replay are there — and `cancel` of an ended job fails in one line."""
import csv
import json

import pytest
from portal_fixtures import SPIN, add_user, start_server

from swarmdeck.console.cli import main
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.sandbox.confinement import probe

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")


def cli(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_submit_verify_run_and_download_the_data(tmp_path, capsys, monkeypatch):
    data = tmp_path / "lab"
    token = add_user(data, "alice", "researcher")
    assert token.startswith("sdk_")
    server = start_server(data, "--fast", "--robots", "4", "--verify-runs", "1", "--workers", "1")
    try:
        script = tmp_path / "spin.py"
        script.write_text(SPIN)
        monkeypatch.setenv("SWARMDECK_TOKEN", token)
        code, out, err = cli(capsys, "submit", str(script), "--robots", "3", "--duration", "2", "--wait", "--json",
                             "--server", server.url)
        job = json.loads(out)
        assert code == 0 and job["state"] == "done" and job["verdict"].startswith("accepted"), (out, err)
        assert err.strip().splitlines()[-1].split()[:2] == [str(job["id"]), "done"]  # states followed on stderr
        code, out, _ = cli(capsys, "jobs", "--json", "--server", server.url)
        assert code == 0 and [(j["id"], j["state"]) for j in json.loads(out)] == [(job["id"], "done")]
        code, out, _ = cli(capsys, "results", str(job["id"]), "-o", str(tmp_path / "out"), "--json",
                           "--server", server.url)
        files = {f["name"] for f in json.loads(out)["files"]}  # `results` waited for the exports
        assert code == 0 and json.loads(out)["exports"] == "ready" and {
            "recording.mcap", "robots.csv", "frames.csv", "replay.html", "video.mp4", "script.log", "report.json",
            "run.json"} <= files
        with open_recording(tmp_path / "out" / "recording.mcap") as rec:
            frames = [frame for _, frame in rec.frames()]
        assert len(frames) >= 55 and frames[-1].poses.shape == (3, 3)  # 2 s at 33 ms
        assert frames[-1].run_time == pytest.approx(2.0, abs=0.04)
        moved = abs(frames[-1].poses[:, 2] - frames[0].poses[:, 2]).max()
        assert moved > 0.3  # the script turned the robots (ω = 0.5 rad/s through the real pipeline)
        with open(tmp_path / "out" / "robots.csv") as f:
            assert len(list(csv.DictReader(f))) == 3 * len(frames)
        run = json.loads((tmp_path / "out" / "run.json").read_text())
        assert run["ended_by"] == "duration" and run["error"] is None
        code, out, err = cli(capsys, "cancel", str(job["id"]), "--server", server.url)
        assert code == 1 and err.count("\n") == 1 and "HTTP 409" in err and "has already ended (done)" in err
        code, _, err = cli(capsys, "jobs", "--server", server.url, "--token", "sdk_wrong")
        assert code == 1 and "HTTP 401" in err
    finally:
        assert server.stop() == 0
    log = "".join(server.output)
    assert "stopped (robots stopped)" in log and "viser" not in log  # no banner of the replay's export


def test_client_usage_errors_exit_2(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("SWARMDECK_TOKEN", raising=False)
    monkeypatch.delenv("SWARMDECK_SERVER", raising=False)
    script = tmp_path / "s.py"
    script.write_text(SPIN)
    assert cli(capsys, "jobs", "--server", "http://127.0.0.1:9")[0] == 2  # no token
    assert cli(capsys, "jobs", "--token", "t")[0] == 2  # no server
    code, _, err = cli(capsys, "submit", str(script), "--server", "http://127.0.0.1:9", "--token", "t")
    assert code == 2 and "--robots N --duration S" in err
    code, _, err = cli(capsys, "submit", str(tmp_path / "nope.py"), "--server", "http://127.0.0.1:9", "--token", "t")
    assert code == 2 and "does not exist" in err
    code, _, err = cli(capsys, "jobs", "--server", "http://127.0.0.1:9", "--token", "t")  # nobody listens there
    assert code == 1 and "cannot reach the server" in err
