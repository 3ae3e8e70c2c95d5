"""Other local users read nothing of the portal's: after a job was verified, ran on the (simulated, --fast) arena and
its exports were written by `swarmdeck server` in its own process, the data folder and every folder in it are 0700
and every file is 0600 — the database, the script, the recording, the CSV, the replay, the video, the logs, the
reports. An older data folder with wider modes is closed when the server opens it."""
import os
import stat
import time

import httpx
import pytest
from portal_fixtures import SPIN, add_user, manifest, start_server, wait_for_state

from swarmdeck.console.portal.db import Database
from swarmdeck.console.sandbox.confinement import probe

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")


def modes(root) -> dict[str, int]:
    """path relative to ``root`` -> permission bits, for ``root`` and everything under it."""
    out = {".": stat.S_IMODE(os.lstat(root).st_mode)}
    for folder, dirs, files in os.walk(root):
        for name in dirs + files:
            path = os.path.join(folder, name)
            out[os.path.relpath(path, root)] = stat.S_IMODE(os.lstat(path).st_mode)
    return out


def test_every_file_the_server_writes_is_0600_in_0700_folders(tmp_path):
    data = tmp_path / "lab"
    token = add_user(data, "alice", "researcher")  # `swarmdeck users add` creates the folder and the database
    assert stat.S_IMODE(os.stat(data).st_mode) == 0o700
    server = start_server(data, "--fast", "--robots", "3", "--verify-runs", "1", "--workers", "1")
    try:
        import json

        with httpx.Client(base_url=server.url, headers={"Authorization": f"Bearer {token}"}, timeout=30) as c:
            r = c.post("/api/jobs", files={"script": ("spin.py", SPIN)},
                       data={"manifest": json.dumps(manifest(robots=2, duration=1.0))})
            assert r.status_code == 201, r.text
            jid = r.json()["id"]
            job = wait_for_state(c, jid, ("done", "failed", "rejected"), timeout=180)
            assert job["state"] == "done", (job["reason"], job)
            deadline = time.monotonic() + 180
            while c.get(f"/api/jobs/{jid}").json()["exports"] == "writing" and time.monotonic() < deadline:
                time.sleep(0.1)
            assert c.get(f"/api/jobs/{jid}").json()["exports"] == "ready"
            names = {f["name"] for f in c.get(f"/api/jobs/{jid}/files").json()}
        assert {"script.log", "recording.mcap", "robots.csv", "replay.html", "video.mp4", "report.json",
                "report.html", "run.json", "manifest.json"} <= names
        found = modes(data)
        folder = f"jobs/{jid}"
        assert {"portal.sqlite3", folder, f"{folder}/script.py", f"{folder}/recording.mcap",
                f"{folder}/video.mp4"} <= set(found)
        wrong = {path: oct(mode) for path, mode in found.items()
                 if mode != (0o700 if os.path.isdir(os.path.join(data, path)) else 0o600)}
        assert wrong == {}, wrong
    finally:
        assert server.stop() == 0


def test_an_older_data_folder_is_closed_when_opened(tmp_path):
    data = tmp_path / "old"
    Database(data).close()
    os.chmod(data, 0o755)
    os.chmod(data / "portal.sqlite3", 0o644)
    Database(data).close()
    assert stat.S_IMODE(os.stat(data).st_mode) == 0o700
    assert stat.S_IMODE(os.stat(data / "portal.sqlite3").st_mode) == 0o600
