"""kill -9 of `swarmdeck server` during a run, then a restart on the same data folder: the job that was running
is `interrupted` with its partial recording recovered and readable, the job behind it is still in the queue and
runs, the database is intact."""
import json
import os
import signal
import time

import httpx
import pytest
from mqtt_broker import wait_until
from portal_fixtures import SPIN, add_user, manifest, start_server, wait_for_state

from swarmdeck.console.portal.db import Database
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.sandbox.confinement import probe

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")


def test_kill_9_during_a_run_then_restart(tmp_path):
    data = tmp_path / "lab"
    token = add_user(data, "alice", "researcher")
    server = start_server(data, "--robots", "4", "--verify-runs", "1", "--workers", "1")  # real time
    try:
        c = httpx.Client(base_url=server.url, headers={"Authorization": f"Bearer {token}"}, timeout=30)
        post = lambda **m: c.post("/api/jobs", files={"script": ("spin.py", SPIN)},  # noqa: E731
                                  data={"manifest": json.dumps(manifest(**m))}).json()["id"]
        running = post(name="long", robots=3, duration=10.0)
        wait_for_state(c, running, ("running",))
        queued = post(name="next", robots=2, duration=0.5)
        recording = data / "jobs" / str(running) / "recording.mcap"
        deadline = time.monotonic() + 30
        while not (recording.is_file() and recording.stat().st_size > 20000):  # some chunks on disk
            assert time.monotonic() < deadline, "the recording did not grow"
            time.sleep(0.05)
        os.kill(server.proc.pid, signal.SIGKILL)
        server.proc.wait(timeout=10)
    finally:
        server.stop()
    db = Database(data)
    assert db.check() == "ok"
    states = {r["id"]: r["state"] for r in db.query("SELECT id, state FROM jobs")}
    assert states[running] == "running" and states[queued] in ("awaiting verification", "verifying", "awaiting approval", "in arena queue")
    db.close()

    server = start_server(data, "--robots", "4", "--verify-runs", "1", "--workers", "1", "--fast")
    try:
        assert any(f"job {running} was on the arena" in line for line in server.output)
        c = httpx.Client(base_url=server.url, headers={"Authorization": f"Bearer {token}"}, timeout=30)
        job = c.get(f"/api/jobs/{running}").json()
        assert job["state"] == "interrupted" and "partial recording kept" in job["reason"]
        assert wait_until(lambda: c.get(f"/api/jobs/{running}").json()["exports"] != "writing", timeout=120,
                          what="the exports of the recovered recording") and \
            c.get(f"/api/jobs/{running}").json()["exports"] == "ready"
        names = {f["name"] for f in c.get(f"/api/jobs/{running}/files").json()}
        assert {"recording.mcap", "recording.partial.mcap", "robots.csv", "run.json"} <= names
        got = c.get(f"/api/jobs/{running}/files/recording.mcap")
        (tmp_path / "got.mcap").write_bytes(got.content)
        with open_recording(tmp_path / "got.mcap") as rec:
            frames = [f for _, f in rec.frames()]
            assert not rec.warnings  # recovered: a clean, indexed file
        assert len(frames) > 10 and frames[-1].poses.shape == (3, 3) and frames[-1].run_time < 10
        assert wait_for_state(c, queued, ("done",))["state"] == "done"
    finally:
        assert server.stop() == 0
    db = Database(data)
    assert db.check() == "ok" and db.query_one("SELECT COUNT(*) FROM jobs")[0] == 2
