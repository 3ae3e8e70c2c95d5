"""kill -9 of `swarmdeck server` while it verifies a job: the verification pool's worker process and the fork
server it started end with it (PR_SET_PDEATHSIG), as a real deployment needs — no process group is killed here.
Before, both outlived the server as orphans."""
import json
import os
import signal
from pathlib import Path

import httpx
import pytest
from mqtt_broker import wait_until
from portal_fixtures import add_user, manifest, start_server, wait_for_state

from swarmdeck.console.sandbox.confinement import probe

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

SLOW = ("import time\n"  # each tick well inside the 1 s verification budget; the whole verification takes minutes
        "def experiment(arena):\n"
        "    while True:\n"
        "        time.sleep(0.05)\n"
        "        arena.step()\n")


def children(pid: int) -> dict[int, str]:
    """The live (not zombie) child processes of ``pid``: pid -> command line."""
    found = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            cmdline = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if int(stat[1]) == pid and stat[0] != "Z":
            found[int(entry.name)] = cmdline
    return found


def alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def test_the_verification_pool_ends_with_a_killed_server(tmp_path):
    data = tmp_path / "lab"
    token = add_user(data, "alice", "researcher")
    server = start_server(data, "--fast", "--verify-runs", "1", "--workers", "1")
    try:
        c = httpx.Client(base_url=server.url, headers={"Authorization": f"Bearer {token}"}, timeout=30)
        jid = c.post("/api/jobs", files={"script": ("slow.py", SLOW)},
                     data={"manifest": json.dumps(manifest(name="slow", robots=2, duration=60.0))}).json()["id"]
        wait_for_state(c, jid, ("verifying",))

        def pool() -> tuple[int, int] | None:  # (the pool's worker, the fork server it started), once both run
            workers = [p for p, cmd in children(server.proc.pid).items() if "multiprocessing" in cmd
                       and "resource_tracker" not in cmd]
            for worker in workers:
                zygotes = [p for p, cmd in children(worker).items() if "swarmdeck.console.sandbox.zygote" in cmd]
                if zygotes:
                    return worker, zygotes[0]
            return None

        worker, zygote = wait_until(pool, timeout=90, what="the verification worker and its fork server")
        assert wait_for_state(c, jid, ("verifying",), timeout=1)["state"] == "verifying"  # still at work
        os.kill(server.proc.pid, signal.SIGKILL)
        server.proc.wait(timeout=10)
        wait_until(lambda: not alive(worker) and not alive(zygote), timeout=30,
                   what="the orphaned worker and fork server to end")
    finally:
        server.stop()
