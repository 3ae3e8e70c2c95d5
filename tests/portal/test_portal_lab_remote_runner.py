"""Remote arena runners (issue 30 items 2 and 4): an arena on "another machine" — `swarmdeck runner` as a real
subprocess over loopback HTTP — pulls its jobs from the portal and pushes the recording and results; a second
runner for the same arena is refused; a runner that sends results for a job it does not hold, or comes back with
a stale lease, changes nothing; a runner killed with -9 mid-job leaves the job interrupted with its partial
recording recovered, and the arena free for the next runner."""
import json
import os
import signal
import subprocess

import pytest
from lab_fixtures import make_lab, queued, until
from portal_fixtures import CLI, SPIN

from swarmdeck.console.portal.arenas import ArenaSpec
from swarmdeck.console.portal.exports import JobExports
from swarmdeck.console.portal.remote import LeaseReaper
from swarmdeck.console.sandbox.confinement import probe

ARENAS = (ArenaSpec("floor", "simulated", robots=6), ArenaSpec("annex", "physical", robots=4, remote=True))


@pytest.fixture
def lab2(tmp_path):
    p = make_lab(tmp_path, ARENAS, runner_lease_s=3.0)
    exports = JobExports(p.service, video=False)
    p.service.remote.exports = exports
    reaper = LeaseReaper(p.service.remote, period_s=0.2).start()
    try:
        yield p
    finally:
        reaper.stop()
        exports.stop()
        p.server.stop()
        p.service.close()


def runner(lab, tmp_path, *extra):
    env = {**os.environ, "SWARMDECK_TOKEN": lab.tokens["op1"]}
    return subprocess.Popen([*CLI, "runner", "--portal", lab.url, "--arena", "annex", "--work", str(tmp_path / "work"),
                             *extra], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
                            start_new_session=True)


def stop(proc):
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    return proc.stdout.read() if proc.stdout else ""


needs_jail = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")


@needs_jail
def test_a_remote_runner_runs_its_arenas_jobs_and_a_second_one_is_refused(lab2, tmp_path):
    svc = lab2.service
    job = queued(lab2, "alice", robots=3, duration=1.0, arena="annex")
    other = queued(lab2, "bob", robots=3, duration=1.0, needs="simulated")  # the floor's: no runner there
    with lab2.client("alice") as c:
        assert c.get(f"/api/jobs/{job}").json()["eta_start"] is None  # the annex has no runner yet: no estimate
    proc = runner(lab2, tmp_path, "--fast")
    try:
        until(lambda: svc.job_state(job) == "done", timeout=180, what=f"job {job} done ({svc.job_state(job)})")
        done = svc.store.get(job)
        assert done.placed == "annex" and svc.store.holder_of(job) is not None
        folder = svc.job_dir(job)
        assert json.loads((folder / "run.json").read_text())["ended_by"] in ("script", "duration")
        assert (folder / "recording.mcap").stat().st_size > 0 and (folder / "script.log").is_file()
        from swarmdeck.console.recording.reader import open_recording

        with open_recording(folder / "recording.mcap") as rec:
            frames = [f for _, f in rec.frames()]
        assert frames and frames[-1].poses.shape == (3, 3)
        assert svc.job_state(other) == "in arena queue"  # the floor has no runner: never taken by the annex
        second = runner(lab2, tmp_path / "b", "--fast")
        assert second.wait(60) == 1
        assert "held by another runner" in stop(second)
        with lab2.client("op1") as op:
            arenas = {a["name"]: a for a in op.get("/api/arenas").json()}
        assert arenas["annex"]["connected"] is True and arenas["annex"]["remote"] is True
    finally:
        out = stop(proc)
    assert "swarmdeck runner: arena annex" in out


def test_results_from_a_runner_that_does_not_hold_the_job_change_nothing(lab2):
    svc = lab2.service
    a = queued(lab2, "alice", robots=2, duration=5.0, arena="annex")
    b = queued(lab2, "bob", robots=2, duration=5.0, arena="floor")
    with lab2.client("op1") as op, lab2.client("alice") as researcher:
        assert researcher.post("/api/runner/connect", json={"arena": "annex"}).status_code == 403
        assert op.post("/api/runner/connect", json={"arena": "floor"}).status_code == 422  # not a remote arena
        assert op.post("/api/runner/connect", json={"arena": "moon"}).status_code == 404
        lease = op.post("/api/runner/connect", json={"arena": "annex"}).json()["lease"]
        assert op.post("/api/runner/connect", json={"arena": "annex"}).status_code == 409  # two runners, one arena
        me = {"arena": "annex", "lease": lease}
        nxt = op.post("/api/runner/claim", json=me).json()
        assert nxt["job"]["id"] == a and nxt["claimed"] is False
        assert op.post("/api/runner/claim", json={**me, "job": a}).json()["claimed"] is True
        # the floor's job b is not this runner's: its results, its end, its files are refused
        put = op.put(f"/api/runner/jobs/{b}/files/run.json", params={**me, "offset": 0}, content=b"{}")
        assert put.status_code == 409 and put.json()["field"] == "job"
        assert op.post(f"/api/runner/jobs/{b}/finish", json={**me, "state": "done"}).status_code == 409
        assert op.get(f"/api/runner/jobs/{b}/bundle", params=me).status_code == 409
        assert svc.job_state(b) == "in arena queue" and not (svc.job_dir(b) / "run.json").exists()
        # a stale lease changes nothing either
        stale = {"arena": "annex", "lease": "not-the-lease"}
        r = op.post(f"/api/runner/jobs/{a}/finish", json={**stale, "state": "done"})
        assert r.status_code == 409 and r.json()["field"] == "lease"
        # uploads: by offset, only the allowed names
        assert op.put(f"/api/runner/jobs/{a}/files/x.sh", params={**me, "offset": 0}, content=b"x").status_code == 422
        assert op.put(f"/api/runner/jobs/{a}/files/script.log", params={**me, "offset": 0},
                      content=b"hello ").json()["size"] == 6
        gap = op.put(f"/api/runner/jobs/{a}/files/script.log", params={**me, "offset": 9}, content=b"world")
        assert gap.status_code == 409 and "offset 6" in gap.json()["error"]
        assert op.put(f"/api/runner/jobs/{a}/files/script.log", params={**me, "offset": 6},
                      content=b"world").json()["size"] == 11
        assert (svc.job_dir(a) / "script.log").read_bytes() == b"hello world"
        assert op.post(f"/api/runner/jobs/{a}/running", json=me).json()["ok"] is True
        assert op.post(f"/api/runner/jobs/{a}/finish", json={**me, "state": "done"}).json()["state"] == "done"
        # the job ended: sending results for it again is refused
        assert op.post(f"/api/runner/jobs/{a}/finish", json={**me, "state": "failed"}).status_code == 409
    assert svc.job_state(a) == "done"


@needs_jail
def test_a_runner_killed_mid_job_leaves_it_interrupted_with_its_recording_and_the_arena_free(lab2, tmp_path):
    svc = lab2.service
    job = queued(lab2, "alice", robots=2, duration=30.0, arena="annex")
    proc = runner(lab2, tmp_path)  # real time: the job runs 30 s
    try:
        until(lambda: svc.job_state(job) == "running", timeout=120, what="the job to run")
        rec = svc.job_dir(job) / "recording.mcap"
        until(lambda: rec.is_file() and rec.stat().st_size > 20_000, timeout=60, what="the recording to arrive")
        os.killpg(proc.pid, signal.SIGKILL)  # the runner, its sandbox, everything it started
        proc.wait(30)
        until(lambda: svc.job_state(job) == "interrupted", timeout=60, what="the job to be interrupted")
        ended = svc.store.get(job)
        assert "stopped answering" in ended.reason
        folder = svc.job_dir(job)
        until(lambda: (folder / "run.json").is_file(), timeout=60, what="the recovery")  # after the state change
        assert (folder / "recording.partial.mcap").is_file()
        from swarmdeck.console.recording.reader import open_recording

        with open_recording(folder / "recording.mcap") as r:
            frames = [f for _, f in r.frames()]
        assert len(frames) > 10 and frames[0].poses.shape == (2, 3)
        assert json.loads((folder / "run.json").read_text())["ended_by"] == "interrupted"
        # the arena is free again: a new runner takes it and runs the next job
        nxt = queued(lab2, "bob", robots=2, duration=0.5, arena="annex")
        again = runner(lab2, tmp_path / "again", "--fast")
        try:
            until(lambda: svc.job_state(nxt) == "done", timeout=180, what="the next job on a new runner")
        finally:
            stop(again)
    finally:
        stop(proc)
    assert SPIN  # the jobs ran the portal fixtures' spinning script


def test_a_runner_that_comes_back_after_its_lease_ran_out_cannot_finish_its_stale_job(lab2):
    svc = lab2.service
    job = queued(lab2, "alice", robots=2, duration=5.0, arena="annex")
    with lab2.client("op1") as op:
        old = {"arena": "annex", "lease": op.post("/api/runner/connect", json={"arena": "annex"}).json()["lease"]}
        assert op.post("/api/runner/claim", json={**old, "job": job}).json()["claimed"] is True
        assert op.post(f"/api/runner/jobs/{job}/running", json=old).json()["ok"] is True
        # the runner goes silent (a network cut): the reaper interrupts its job once the lease is 3 s old
        until(lambda: svc.job_state(job) == "interrupted", timeout=60, what="the lease to run out")
        assert op.post("/api/runner/heartbeat", json={**old, "job": job}).status_code == 409
        new = op.post("/api/runner/connect", json={"arena": "annex"}).json()
        assert new["lease"] != old["lease"]
        mine = {"arena": "annex", "lease": new["lease"]}
        assert op.post("/api/runner/heartbeat", json={**mine, "job": job}).json()["end_job"] is True
        r = op.post(f"/api/runner/jobs/{job}/finish", json={**mine, "state": "done"})
        assert r.status_code == 409 and r.json()["field"] == "job"
    assert svc.job_state(job) == "interrupted"


def test_the_runner_command_says_what_is_missing_or_unreachable(tmp_path, capsys, monkeypatch):
    from swarmdeck.console.cli import main

    monkeypatch.delenv("SWARMDECK_TOKEN", raising=False)
    assert main(["runner", "--portal", "http://127.0.0.1:9", "--arena", "annex", "--work", str(tmp_path)]) == 2
    assert "no access token" in capsys.readouterr().err
    if probe() is None:
        assert main(["runner", "--portal", "http://127.0.0.1:9", "--arena", "annex", "--token", "sdk_x",
                     "--work", str(tmp_path)]) == 1
        assert "cannot reach the portal" in capsys.readouterr().err


def test_the_runner_cli_gives_the_callers_umask_back(tmp_path, monkeypatch):
    """`swarmdeck runner` writes privately (umask 077) but restores the caller's umask: run in-process (as the CLI
    tests do) it left 077 behind, and every later test of that worker made files no jail could read."""
    import os

    from swarmdeck.console.cli import main

    monkeypatch.delenv("SWARMDECK_TOKEN", raising=False)
    before = os.umask(0o022)
    try:
        main(["runner", "--portal", "http://127.0.0.1:9", "--arena", "annex", "--token", "sdk_x",
              "--work", str(tmp_path / "w"), "--trusted"])
        assert os.umask(0o022) == 0o022
    finally:
        os.umask(before)
