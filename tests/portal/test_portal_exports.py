"""A job's exports (CSV, HTML replay, video) are written off the arena thread: the next job runs while they are
still being written, the job says where they are (writing → ready | failed, with the error in run.json), an
export a stopped server left unfinished is written on the next start, and stopping kills the export at once
without leaving a partial file among the results."""
import csv
import json
from pathlib import Path

import av
import pytest
from mqtt_broker import wait_until
from portal_fixtures import SPIN, manifest, wait_for_state
from recording_synth import write_synthetic_session

from swarmdeck.console.cli import main
from swarmdeck.console.portal.exports import JobExports
from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.portal.service import PortalConfig, PortalService
from swarmdeck.console.sandbox.confinement import probe

confined = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")


def ended_job(portal, who="alice", state="done"):
    """A job moved through the state machine to ``state`` (no run), as the arena runner would leave it."""
    svc = portal.service
    jid = portal.submit(who).json()["id"]
    with svc.db.transaction() as tx:
        for s in ("verifying", "awaiting approval", "in arena queue", "setting up", "running", state):
            svc.db.transition(tx, jid, s, **({"verdict": "accepted"} if s == "awaiting approval" else {}))
    return jid


def run_json(portal, jid):
    return json.loads((portal.service.job_dir(jid) / "run.json").read_text())


@confined
def test_the_next_job_runs_while_the_exports_wait_and_a_restart_writes_them(portal, tmp_path, capsys):
    svc = portal.service
    runner = ArenaRunner(svc, ArenaSettings(fleet=6, fast=True, seed=3), poll_s=0.05)
    runner.exports.stop()  # exports never get written by this server: as if they took forever
    svc.arena = runner
    ids = [portal.submit("alice", duration=0.5).json()["id"] for _ in range(2)]
    with svc.db.transaction() as tx:
        for jid in ids:
            for s in ("verifying", "awaiting approval", "in arena queue"):
                svc.db.transition(tx, jid, s, **({"verdict": "accepted"} if s == "awaiting approval" else {}))
    runner.start()
    try:
        with portal.client("alice") as c:
            for jid in ids:
                assert wait_for_state(c, jid, ("done",))["exports"] == "writing"
            files = {f["name"] for f in c.get(f"/api/jobs/{ids[0]}/files").json()}
            assert "recording.mcap" in files and "robots.csv" not in files  # the second job did not wait for them
            r = c.get(f"/api/jobs/{ids[0]}/files/robots.csv")
            assert r.status_code == 503 and "still being written" in r.json()["error"]
            assert c.get(f"/api/jobs/{ids[0]}/files/video.mp4").status_code == 503
        client = ["--server", portal.url, "--token", portal.tokens["alice"]]
        code = main(["results", str(ids[0]), "-o", str(tmp_path / "now"), "--no-wait", "--json", *client])
        out, err = capsys.readouterr()
        assert code == 0 and "exports still being written" in err and json.loads(out)["exports"] == "writing"
        assert "recording.mcap" in {f["name"] for f in json.loads(out)["files"]}
        code = main(["results", str(ids[0]), "-o", str(tmp_path / "later"), "--timeout", "0.2", *client])
        assert code == 1 and "still being written after 0.2 s" in capsys.readouterr().err
    finally:
        runner.stop()
    exports = JobExports(svc)  # the next start: unfinished exports are written again
    try:
        assert exports.resume() == ids and exports.wait_idle(240)
    finally:
        exports.stop()
    for jid in ids:
        assert svc.job(svc.accounts.user_named("alice"), jid).exports == "ready"
        run = run_json(portal, jid)
        assert run["ended_by"] == "duration" and run["export_error"] is None
        assert run["exports"] == ["capsule.zip", "robots.csv", "frames.csv", "replay.html", "video.mp4"] and run["exports_s"] > 0
        folder = svc.job_dir(jid)
        with open(folder / "frames.csv") as f:
            assert len(list(csv.DictReader(f))) == run["ticks"] + 1  # every tick and the starting poses
        assert "<html" in (folder / "replay.html").read_text()[:2000].lower()
        with av.open(str(folder / "video.mp4")) as v:
            assert v.streams.video[0].codec_context.name == "h264"
        assert not (folder / ".exports").exists()


def test_a_failed_export_is_noted_in_run_json_and_the_others_go_on(portal):
    svc = portal.service
    bad, good = ended_job(portal), ended_job(portal, "bob")
    (svc.job_dir(bad) / "recording.mcap").write_bytes(b"\x89MCAP0\r\n" + b"not a recording" * 100)
    (svc.job_dir(bad) / "run.json").write_text(json.dumps({"ended_by": "duration"}))
    write_synthetic_session(svc.job_dir(good) / "recording.mcap", n_robots=2, seconds=1.0, dt=0.05)
    exports = JobExports(svc, video=False)
    try:
        exports.submit(bad)
        exports.submit(good)
        assert exports.wait_idle(240)
    finally:
        exports.stop()
    with portal.client("alice") as c:
        job = c.get(f"/api/jobs/{bad}").json()
        assert job["exports"] == "failed" and job["state"] == "done"
    run = run_json(portal, bad)
    assert run["ended_by"] == "duration" and run["exports"] == [] and run["export_error"].startswith("recording: ")
    assert not {"robots.csv", "replay.html"} & {p.name for p in svc.job_dir(bad).iterdir()}
    assert run_json(portal, good)["exports"] == ["robots.csv", "frames.csv", "replay.html"]
    with portal.client("bob") as c:
        assert c.get(f"/api/jobs/{good}").json()["exports"] == "ready"


def test_stopping_kills_the_export_and_leaves_no_partial_file(portal):
    svc = portal.service
    jid = ended_job(portal)
    folder = svc.job_dir(jid)
    write_synthetic_session(folder / "recording.mcap", n_robots=6, seconds=40.0, dt=0.05)  # 40 s of video
    exports = JobExports(svc)
    exports.submit(jid)
    child = wait_until(lambda: exports._proc, timeout=30, what="the export process")
    wait_until(lambda: (folder / ".exports").is_dir(), timeout=60, what="the export to begin writing")
    exports.stop()
    assert child.poll() is not None and not exports._thread.alive  # killed, not waited for
    assert svc.exports_in("writing") == [jid]  # redone on the next start
    assert not (folder / "video.mp4").exists()  # a video cut short stays in .exports/, cleared on the next start


def test_a_data_folder_given_as_a_relative_path_is_exported(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # `swarmdeck server` defaults to ./swarmdeck-data
    svc = PortalService(PortalConfig(data=Path("lab")))
    try:
        user, _ = svc.accounts.add_user("alice", "researcher")
        jid = svc.submit(user, "spin.py", SPIN.encode(), json.dumps(manifest())).id
        write_synthetic_session(svc.job_dir(jid) / "recording.mcap", n_robots=2, seconds=0.5, dt=0.05)
        exports = JobExports(svc, video=False)
        try:
            exports.submit(jid)
            assert exports.wait_idle(240)
        finally:
            exports.stop()
        assert svc.job(user, jid).exports == "ready" and (tmp_path / "lab" / "jobs" / str(jid) / "robots.csv").is_file()
    finally:
        svc.close()
